#include "db/leaf_reader.h"

#include <algorithm>

#include "schema/octant.h"

namespace weaver {

Status LeafReader::open(BTree& octants, uint64_t from, bool payloads) {
  file_ = octants.file_name();
  WEAVER_RETURN_IF_ERROR(payloads ? octants.seek_cursor(from, &cursor_)
                                  : octants.seek_keys(from, &cursor_));
  return cursor_.valid() ? check_current() : Status::Ok();
}

Status LeafReader::check_current() { return check_key(cursor_.key()); }

Status LeafReader::check_key(uint64_t key) const {
  if (!octant_key_is_valid(key)) {
    return Status::Corruption(file_ + ": invalid octant key " + std::to_string(key));
  }
  return Status::Ok();
}

Status LeafReader::overlap(uint64_t prev, uint64_t key) const {
  return Status::InvalidArgument("octants " + describe_octant(octant_from_key(prev)) + " and " +
                                 describe_octant(octant_from_key(key)) + " overlap");
}

Status LeafReader::next() {
  const uint64_t prev = cursor_.key();
  WEAVER_RETURN_IF_ERROR(cursor_.next());
  if (!cursor_.valid()) return Status::Ok();
  WEAVER_RETURN_IF_ERROR(check_current());
  // A later key inside prev's subtree key range is a descendant of prev.
  if (cursor_.key() < octant_key_subtree_end(prev)) return overlap(prev, cursor_.key());
  return Status::Ok();
}

namespace {

// By a key's slot (its low 7 bits), in units of key >> 7 (the Morton code
// over 8): the bits below its level's cell, which a valid key has clear,
// and the span of its subtree (0 at level 20, whose subtree ends at the
// next key).
struct SlotTables {
  uint64_t low[128], span[128];
  constexpr SlotTables() : low(), span() {
    for (uint64_t slot = 0; slot < 128; ++slot) {
      const bool below_20 = slot < kKeyLevel20Slot;
      low[slot] = below_20 ? (uint64_t{1} << (57 - 3 * slot)) - 1 : 0;
      span[slot] = below_20 ? uint64_t{1} << (57 - 3 * slot) : 0;
    }
  }
};
constexpr SlotTables kSlots;

// Whether key is valid and starts at or past the end of prev's subtree (prev
// valid): & for &&, so that a run of keys is checked without branches.  A
// level 20 prev's subtree ends at the next key: past it, key > prev.
inline bool key_follows(uint64_t prev, uint64_t key) {
  const uint64_t slot = key & 127, prev_slot = prev & 127;
  const uint64_t units = key >> 7, prev_end = (prev >> 7) + kSlots.span[prev_slot];
  const bool past = (units > prev_end) | ((units == prev_end) & (key > prev));
  return ((units & kSlots.low[slot]) == 0) & (slot < kKeyLevel20Slot + 8) & past;
}

}  // namespace

Status LeafReader::take(size_t most, uint64_t stop, std::vector<uint64_t>* out) {
  size_t taken = 0;
  while (taken < most && cursor_.valid()) {
    uint32_t n = 0;
    const uint64_t* keys = cursor_.keys_in_leaf(&n);
    if (octant_key_morton(keys[0]) >= stop) return Status::Ok();
    // The current key was checked when the reader reached it; the rest of
    // the leaf's are checked here, each against the one before.
    uint32_t k = uint32_t(std::min<size_t>(n, most - taken));
    // Sorted keys have sorted Morton codes: the stop is found by a search
    // (a table of keys out of order fails the checks below all the same).
    if (stop != UINT64_MAX && octant_key_morton_of_any(keys[k - 1]) >= stop) {
      k = static_cast<uint32_t>(std::partition_point(keys + 1, keys + k,
                                                     [stop](uint64_t key) {
                                                       return octant_key_morton_of_any(key) < stop;
                                                     }) -
                                keys);
    }
    // All the keys checked at once, without a branch a key; the first that
    // fails is found again for its message.  (A Status made and tested for
    // each key was a third of the reading, a branch each a third of what
    // was left.)
    bool good = true;
    for (uint32_t i = 1; i < k; ++i) good &= key_follows(keys[i - 1], keys[i]);
    if (!good) {
      for (uint32_t i = 1; i < k; ++i) {
        if (!octant_key_is_valid(keys[i])) return check_key(keys[i]);
        if (keys[i] < octant_key_subtree_end(keys[i - 1])) return overlap(keys[i - 1], keys[i]);
      }
    }
    out->insert(out->end(), keys, keys + k);
    taken += k;
    // The last taken is the reader's key before moving on: next() checks
    // the one it lands on against it.
    if (k > 1) WEAVER_RETURN_IF_ERROR(cursor_.skip(k - 1));
    WEAVER_RETURN_IF_ERROR(next());
  }
  return Status::Ok();
}

}  // namespace weaver
