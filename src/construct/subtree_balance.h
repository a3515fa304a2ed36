// The 2:1 balance of one subtree of construct's descent, in memory, while
// its leaves are hot: construct writes the balanced octree directly, the
// same table that `construct --unbalanced` then `weaver balance` write.
//
// Which leaves outside the subtree can refine a leaf o inside it?  Balance
// refines o only through a chain of required octants c(m+1), ..., c(k-1)
// that starts at an input leaf q = c(k) of level k and ends inside o (level
// m), each c(j) a face or edge neighbour of P(j), the parent of c(j+1), each
// but the last made by splitting an input leaf (balance/closure.h).  P(j)
// touches c(j) and has its edge E(j), so c(j+1) lies in c(j) grown by E(j)
// on every side, and q in o grown by E(m+1) + ... + E(k-1) < E(m): the
// insulation layer of Isaac, Burstedde and Ghattas's parallel balance (the
// 3 x 3 x 3 block of o-sized octants around o; balance_shard.h).  So o's
// refinement depends only on the input leaves that meet that open block,
// and the block leaves the subtree only where o touches its boundary.  The
// balancer
//   1. grows the subtree's box, side by side, by the edge of the largest
//      leaf touching that side, and collects the input leaves outside the
//      subtree that meet it, by descending the model again (the descent is
//      a function of the octant: no table is read);
//   2. ripples the requirements of these and the subtree's own leaves from
//      fine to coarse (a leaf asks for the octants one level coarser that
//      it touches; an octant made by a split, for all of its parent's face
//      and edge neighbours), keeping the octants that lie strictly inside
//      a leaf: the ones the balance creates;
//   3. splits each own leaf just enough to resolve what was created inside
//      it.  A new leaf takes the model's material at its centre (or its
//      parent's, where weaver balance would keep the parent's).
// Any extra leaf collected only adds requirements the whole octree has too,
// so the result is exact; the tests compare it with weaver balance.  A
// subtree whose leaves span two levels, with the model's bounds keeping
// every leaf around it no finer than their finer one, cannot be split by
// any of them: it skips all three steps (stands(), in the .cc).
#pragma once

#include <array>
#include <cstdint>
#include <utility>
#include <vector>

#include "construct/descent.h"
#include "schema/octant.h"
#include "util/local_ripple.h"

namespace weaver {

class SubtreeBalancer {
 public:
  // fill_material: new leaves take the model's material at their centre;
  // else a copy of the leaf they split.
  SubtreeBalancer(const Descent& descent, bool fill_material);

  // Makes *leaves (root's subtree, in key order, as visit_subtree gives
  // them) their refinement in the balanced octree: the leaves it splits
  // are left out of its pieces, their parts added (SubtreeLeaves::pieces);
  // levels and elements follow, the edge and ppw figures of the descent
  // stay.
  void balance(const Octant& root, SubtreeLeaves* leaves);

  // Leaves outside the subtrees collected, summed over the calls.
  uint64_t neighbours_collected() const { return collected_count_; }

 private:
  // Whether the balance can be known to split none of the leaves (the
  // grown box made).
  bool stands(const SubtreeLeaves& leaves) const;
  void grow_box(const Octant& root, const SubtreeLeaves& leaves);
  void collect(const Octant& x, const Judgement& j, const Octant& root);
  // The same under an x whose leaves are all of `level`
  // (Descent::uniform_leaf_level), without asking the model.
  void collect_level(const Octant& x, int level, const Octant& root);
  bool wanted(const Octant& x, const Octant& root) const;
  void refine(SubtreeLeaves* leaves);
  void add_leaf(SubtreeLeaves* leaves, uint64_t key, bool is_new, const std::byte* parent_payload);
  void fill_materials(SubtreeLeaves* leaves);

  const Descent& descent_;
  const bool fill_;
  int64_t box_lo_[3] = {}, box_hi_[3] = {};  // the grown box, ticks, half-open
  std::vector<Octant> blocks_;               // the blocks the grown box meets, in key order
  std::vector<uint64_t> collected_;          // leaves around the subtree, in key order
  std::vector<uint64_t> local_;              // those and the subtree's leaves, in key order
  LocalRipple ripple_;
  std::vector<uint64_t> created_;
  std::vector<size_t> fresh_;  // where refine's new leaves are among the added, to fill
  // The others: where, and their parent leaf's record.
  std::vector<std::pair<size_t, const std::byte*>> copied_;
  uint64_t collected_count_ = 0;
};

}  // namespace weaver
