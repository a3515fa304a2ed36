// Merges a stream of material octants, given in key order (Z-order), into
// the coarsest octree that says the same within a tolerance: eight siblings
// become their parent when every field of every one lies within `tolerance`
// (relative) of the smallest value of that field among them, recursively,
// the parent taking their mean.  The bound holds over each merged octant's
// whole subtree (a merged octant keeps the least and greatest values of what
// it covers), so merging never drifts further than the tolerance from the
// input.  Tolerance 0 merges only exactly equal siblings.
//
// Memory: at most 8 pending octants a level (21 levels), whatever the input.
// Output is emitted in key order, through the sink, as soon as it is final.
#pragma once

#include <array>
#include <cstdint>
#include <functional>

#include "schema/octant.h"
#include "schema/status.h"

namespace weaver {

inline constexpr int kModelFields = 5;  // vp, vs, rho, qp, qs
using ModelValues = std::array<float, kModelFields>;

class MaterialMerger {
 public:
  using Sink = std::function<Status(uint64_t key, const ModelValues&)>;

  // An octant with the mean of what it covers and the least and greatest
  // of every field there (all three the same for an octant of the input).
  struct Entry {
    Octant octant;
    ModelValues mean, low, high;
  };

  MaterialMerger(double tolerance, int fields, Sink sink)
      : tolerance_(tolerance), fields_(fields), sink_(std::move(sink)) {}
  // Emitting whole entries, bounds and all: a merger of one subtree, whose
  // output another merger takes on (add(const Entry&)) as if it had merged
  // the subtree itself.
  using EntrySink = std::function<Status(const Entry&)>;
  MaterialMerger(double tolerance, int fields, EntrySink sink)
      : tolerance_(tolerance), fields_(fields), entry_sink_(std::move(sink)) {}

  // REQUIRES: octants in strictly increasing key order, none inside an
  // earlier one.
  Status add(const Octant& o, const ModelValues& v) { return add(Entry{o, v, v, v}); }
  // An octant merged already (model/block_merge.h), with its bounds.
  Status add(const Entry& e);
  // Whether eight siblings merge, and the parent they merge into: the rule
  // add() applies, for those who merge ahead of it.
  bool agree(const Entry* eight) const;
  Entry merged(const Octant& parent, const Entry* eight) const;
  // Emits whatever is still pending.  Call once, after the last add.
  Status finish();

  uint64_t emitted() const { return emitted_; }

 private:
  struct Group {  // siblings of one parent, waiting for the rest
    Octant parent;
    int count = 0;
    // Cannot merge (a member or something in one went out already): the
    // rest of the parent's children go out as they come.
    bool broken = false;
    std::array<Entry, 8> members;
  };

  Status push(const Entry& e);
  // Closes the groups at `level` and finer (their siblings will not come).
  Status close_from(int level);
  // Emits the pending members of the groups coarser than `level`, coarsest
  // first, and marks them broken: `finer`, of that level, or something in
  // it is about to be emitted, so its ancestors will never be whole.
  Status break_coarser(int level, const Octant& finer);
  Status emit(const Entry& e);

  double tolerance_;
  int fields_;
  Sink sink_;
  EntrySink entry_sink_;
  std::array<Group, kMaxLevel + 1> groups_{};  // by the members' level
  // No group finer than this holds members or is broken.
  int deepest_ = 0;
  uint64_t emitted_ = 0;
};

}  // namespace weaver
