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

// Each of n leaves (keys in key order) resolved against `created` (key
// order, octants required strictly inside the leaves): copy(i) for a leaf
// with none inside it, as it is; else emit(i, leaf key, is_new) for each
// leaf of its split, in key order.
template <typename Copy, typename Emit>
Status resolve_leaves(const uint64_t* keys, size_t n, const std::vector<uint64_t>& created,
                      const Copy& copy, const Emit& emit) {
  size_t pos = created.empty() || n == 0
                   ? created.size()
                   : std::lower_bound(created.begin(), created.end(), keys[0]) - created.begin();
  for (size_t i = 0; i < n; ++i) {
    const uint64_t key = keys[i];
    while (pos < created.size() && created[pos] <= key) ++pos;
    if (pos == created.size() || created[pos] >= octant_key_subtree_end(key)) {
      WEAVER_RETURN_IF_ERROR(copy(i));
      continue;
    }
    WEAVER_RETURN_IF_ERROR(split_to_resolve(
        key, false, created.size(), [&](size_t j) { return created[j]; }, &pos,
        [&](uint64_t leaf, bool is_new) { return emit(i, leaf, is_new); }));
  }
  return Status::Ok();
}

}  // namespace weaver
