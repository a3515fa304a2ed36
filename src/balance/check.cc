// `weaver balance --check` and verify's balance check: the closure without
// propagation, and the first required octant strictly inside a leaf named
// as a violation.
#include <unistd.h>

#include "balance/balance.h"
#include "balance/closure.h"
#include "schema/octant.h"

namespace weaver {
namespace {

// The first required octant strictly inside a leaf is a violation.
Status find_violation(BTree& leaves, KeyTagSource& required, BalanceResult* r) {
  return for_each_leaf(
      leaves, required, [&](const BTreeCursor& c, const std::vector<KeyTag>& inside, bool* stop) {
        if (inside.empty()) return Status::Ok();
        // Without propagation every required octant's tag is a leaf that
        // touches it (see parent_asks.h), two or more levels finer than c.
        const Octant coarse = octant_from_key(c.key());
        const Octant fine = octant_from_key(inside[0].tag);
        r->balanced = false;
        r->violation = "octants " + describe_octant(coarse) + " and " + describe_octant(fine) +
                       " are face or edge neighbours more than one level apart";
        *stop = true;
        return Status::Ok();
      });
}

}  // namespace

Status check_balance(BTree& leaves, const BalanceOptions& o, const std::string& scratch_parent,
                     BalanceResult* r) {
  *r = BalanceResult{};
  const BalanceMemory memory(o.memory);
  ScratchDir scratch{scratch_parent + "/weaver-balance-check-" + std::to_string(::getpid())};
  Closure closure(leaves, memory, scratch.path, o, nullptr, r);
  WEAVER_RETURN_IF_ERROR(closure.build(finest_level_bound(leaves), false));
  return find_violation(leaves, closure.required(), r);
}

}  // namespace weaver
