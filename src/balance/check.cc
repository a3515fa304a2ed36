// `weaver balance --check` and verify's balance check: the closure without
// propagation, and the first required octant strictly inside a leaf named
// as a violation.
#include <unistd.h>

#include <algorithm>

#include "balance/balance.h"
#include "balance/closure.h"
#include "schema/octant.h"

namespace weaver {
namespace {

// The leaf of parent(asker) that touches `coarse`: the leaf holding the
// pixel of parent(asker) nearest to it.  (The asker itself may sit on the far
// side of its parent; the parent is covered by leaves at least as fine.)
Status touching_leaf(BTree& leaves, const Octant& coarse, const Octant& asker, Octant* out) {
  const Octant p = octant_parent(asker);
  const uint32_t s = octant_edge(p), e = octant_edge(coarse);
  const uint32_t lo[3] = {p.x, p.y, p.z}, clo[3] = {coarse.x, coarse.y, coarse.z};
  uint32_t px[3];
  for (int a = 0; a < 3; ++a) {
    if (clo[a] >= lo[a] + s) {
      px[a] = lo[a] + s - 1;  // coarse lies beyond on this axis
    } else if (clo[a] + e <= lo[a]) {
      px[a] = lo[a];  // coarse lies before
    } else {
      px[a] = std::max(lo[a], clo[a]);  // overlapping range: a shared coordinate
    }
  }
  uint64_t key = 0;
  bool found = false;
  WEAVER_RETURN_IF_ERROR(leaves.floor(pixel_key({px[0], px[1], px[2]}), &key, nullptr, &found));
  *out = found ? octant_from_key(key) : asker;
  return Status::Ok();
}

// The first required octant strictly inside a leaf is a violation.
Status find_violation(BTree& leaves, KeyTagSource& required, BalanceResult* r) {
  return for_each_leaf(
      leaves, required, [&](const BTreeCursor& c, const std::vector<KeyTag>& inside, bool* stop) {
        if (inside.empty()) return Status::Ok();
        const Octant coarse = octant_from_key(c.key());
        Octant fine;
        WEAVER_RETURN_IF_ERROR(
            touching_leaf(leaves, coarse, octant_from_key(inside[0].tag), &fine));
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
