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

Status LeafReader::take(size_t most, uint64_t stop, std::vector<uint64_t>* out) {
  size_t taken = 0;
  while (taken < most && cursor_.valid()) {
    uint32_t n = 0;
    const uint64_t* keys = cursor_.keys_in_leaf(&n);
    if (octant_key_morton(keys[0]) >= stop) return Status::Ok();
    // The current key was checked when the reader reached it; the rest of
    // the leaf's are checked here, each against the one before.
    const uint32_t room = uint32_t(std::min<size_t>(n, most - taken));
    uint32_t k = 1;
    for (; k < room && octant_key_morton(keys[k]) < stop; ++k) {
      // The test inline, the Status only for the message: a Status made
      // and tested for each key was a third of the reading.
      if (!octant_key_is_valid(keys[k])) return check_key(keys[k]);
      if (keys[k] < octant_key_subtree_end(keys[k - 1])) return overlap(keys[k - 1], keys[k]);
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
