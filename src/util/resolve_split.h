// The leaves that resolve required octants inside an octant: the octant
// is split, and each child in turn, while a required octant lies strictly
// inside it.  Balance's refinement writer and construct's subtree balance
// both split their leaves this way.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "schema/octant.h"
#include "schema/status.h"

namespace weaver {

// key_of(i) is the i-th of `count` required octant keys, in key order; *pos
// is the first not yet passed, and moves forward (calls for leaves in key
// order share it).  emit(leaf key, is_new) is called for each resulting
// leaf in key order (is_new: made by a split, not `key` itself); the first
// error it returns stops the walk.  Keys all the way: most callers never
// need the octant decoded.
template <typename KeyOf, typename Emit>
Status split_to_resolve(uint64_t key, bool is_new, size_t count, const KeyOf& key_of, size_t* pos,
                        const Emit& emit) {
  const uint64_t end = octant_key_subtree_end(key);
  while (*pos < count && key_of(*pos) <= key) ++*pos;  // key itself is resolved
  if (*pos < count && key_of(*pos) < end) {
    for (int c = 0; c < 8; ++c) {
      WEAVER_RETURN_IF_ERROR(
          split_to_resolve(octant_key_child(key, c), true, count, key_of, pos, emit));
    }
    return Status::Ok();
  }
  return emit(key, is_new);
}

// The last of keys[from, n) below `key`, given keys[from] < key: found by
// strides that double, then halving.
inline size_t last_below(const uint64_t* keys, size_t from, size_t n, uint64_t key) {
  size_t step = 1;
  while (from + step < n && keys[from + step] < key) from += step, step *= 2;
  // keys[from] < key, and keys[from + step] >= key where it exists.
  return std::lower_bound(keys + from + 1, keys + std::min(n, from + step), key) - keys - 1;
}

// Each of n leaves (keys in key order) resolved against `created` (key
// order, octants required strictly inside the leaves): copy(begin, end)
// for each run of leaves with none inside them, as they are; else emit(i,
// leaf key, is_new) for each leaf of leaf i's split, in key order.  Only
// the leaf just before a created octant can hold it, so the leaves between
// are passed over as a run, not looked at one by one (a leaf at a time, the
// walk was most of construct's refine's own time: 2.9% of the 2 Hz
// construct's perf samples).
template <typename CopyRun, typename Emit>
Status resolve_leaves(const uint64_t* keys, size_t n, const std::vector<uint64_t>& created,
                      const CopyRun& copy, const Emit& emit) {
  const uint64_t* c = created.data();
  const size_t m = created.size();
  size_t pos = m == 0 || n == 0 ? m : std::lower_bound(c, c + m, keys[0]) - c;
  size_t i = 0;  // the first leaf not yet passed
  while (i < n) {
    while (pos < m && c[pos] <= keys[i]) ++pos;
    if (pos == m) break;
    // No leaf from i up to j holds a created octant but j may hold c[pos]:
    // one before j would lie between keys[i] and c[pos].
    const size_t j = last_below(keys, i, n, c[pos]);
    if (c[pos] >= octant_key_subtree_end(keys[j])) {
      WEAVER_RETURN_IF_ERROR(copy(i, j + 1));
      i = j + 1;
      continue;
    }
    if (i < j) WEAVER_RETURN_IF_ERROR(copy(i, j));
    WEAVER_RETURN_IF_ERROR(split_to_resolve(
        keys[j], false, m, [&](size_t k) { return c[k]; }, &pos,
        [&](uint64_t leaf, bool is_new) { return emit(j, leaf, is_new); }));
    i = j + 1;
  }
  if (i < n) WEAVER_RETURN_IF_ERROR(copy(i, n));
  return Status::Ok();
}

}  // namespace weaver
