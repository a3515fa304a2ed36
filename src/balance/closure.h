// The closure of balance: the octants that 2:1 balance requires to be
// resolved (covered by leaves at least as fine), found out of core.
//
// Every leaf q at level l requires the octants of level l-1 that it touches
// by a face or an edge (its parent's face and edge neighbours on q's sides)
// to be resolved; so does every required octant that the refinement will
// make a leaf, and its siblings, which are all of its parent's neighbours.
// These requirements ripple from fine to coarse, one level at a time; each
// level's set is sorted and deduplicated out of core, and octants outside
// the domain are dropped (they hold no leaves to balance against).  Every
// requirement is necessary, even where the leaves do not fill their
// parents (holes in the domain), so a refinement that resolves exactly
// these is minimal.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "balance/balance.h"
#include "balance/balance_progress.h"
#include "balance/domain_map.h"
#include "schema/status.h"
#include "sort/key_tag.h"
#include "sort/sorted_spool.h"
#include "storage/btree.h"

namespace weaver {

class ExternalSorter;

// Where the budget goes.  Everything else is sorted already: a level's
// parents arrive as sorted streams (of the leaves, one from each stretch of
// the first scan; of the octants required one level finer), and each
// level's required octants come out of the candidate sorter in order.
class Closure {
 public:
  // leaves: the input octant table, open.  Spools and sorter runs go in scratch_dir.
  // progress may be null.
  // The level passes' neighbour generation and sorts run on options.threads.
  // second_reader, if not null, is another handle on the same table: the
  // first scan then reads half the leaves through it, on a thread of its own.
  Closure(BTree& leaves, const BalanceMemory& memory, const std::string& scratch_dir,
          const BalanceOptions& options, BalanceProgress* progress, BalanceResult* result,
          BTree* second_reader = nullptr);
  ~Closure();

  // Builds the required octants of levels 0..max_level-1.  Without
  // propagation (a check) only the leaves' own requirements are made: enough
  // to tell whether the octree is balanced.
  Status build(int max_level, bool propagate);

  // The required octants, deduplicated, in key order; tag = a leaf that
  // asks (for naming violations).  REQUIRES: build() succeeded.
  KeyTagSource& required() { return *required_merge_; }

 private:
  using Sorters = std::vector<std::unique_ptr<ExternalSorter>>;

  using Spools = std::vector<std::unique_ptr<SortedSpool>>;

  std::unique_ptr<SortedSpool> spool(const std::string& name, int level) const;
  Status scan_leaves(int max_level);
  Status scan_stretch(BTree& leaves, uint64_t from, uint64_t to, Spools& parents,
                      DomainMap::Writer& map, std::atomic<uint64_t>* scanned, bool report,
                      uint64_t* read);
  Status emit_candidates(int l, KeyTagSource& parents, uint64_t parent_count, Sorters& sorters,
                         uint64_t* added);
  Status expand_level(int l, KeyTagSource& parents, uint64_t parent_count, bool propagate);
  // Part way through level l's pass (half emitting, half probing).
  void report(int l, uint64_t step, double f) const {
    if (progress_ != nullptr && step % BalanceProgress::kEvery == 0) progress_->within_level(l, f);
  }

  BTree& leaves_;
  BTree* second_reader_;
  const BalanceMemory& memory_;
  std::string scratch_;
  int threads_;
  size_t parallel_chunk_;
  BalanceProgress* progress_;
  BalanceResult* r_;
  // By level: parents of leaves (a set of spools for each stretch of the
  // first scan), parents of required octants, the required.
  std::vector<Spools> leaf_parents_;
  Spools required_parents_, required_;
  std::unique_ptr<KeyTagMerge> required_merge_;
  std::unique_ptr<DomainMap> domain_;  // built by the first scan
};

// Calls visit(leaf cursor, required octants strictly inside the leaf) for
// every leaf in key order, until visit sets *stop: the merge of the leaves
// with the closure that both the refinement and the check walk.
using LeafVisit = std::function<Status(const BTreeCursor&, const std::vector<KeyTag>&, bool* stop)>;
Status for_each_leaf(BTree& leaves, KeyTagSource& required, const LeafVisit& visit);

// Removes a scratch directory however the run ends.
struct ScratchDir {
  std::string path;
  ~ScratchDir();
};

}  // namespace weaver
