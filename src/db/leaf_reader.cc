#include "db/leaf_reader.h"

#include "schema/octant.h"

namespace weaver {

Status LeafReader::open(BTree& octants, uint64_t from, bool payloads) {
  file_ = octants.file_name();
  WEAVER_RETURN_IF_ERROR(payloads ? octants.seek_cursor(from, &cursor_)
                                  : octants.seek_keys(from, &cursor_));
  return cursor_.valid() ? check_current() : Status::Ok();
}

Status LeafReader::check_current() {
  if (!octant_key_is_valid(cursor_.key())) {
    return Status::Corruption(file_ + ": invalid octant key " + std::to_string(cursor_.key()));
  }
  return Status::Ok();
}

Status LeafReader::next() {
  const uint64_t prev = cursor_.key();
  WEAVER_RETURN_IF_ERROR(cursor_.next());
  if (!cursor_.valid()) return Status::Ok();
  WEAVER_RETURN_IF_ERROR(check_current());
  // A later key inside prev's subtree key range is a descendant of prev.
  if (cursor_.key() < octant_key_subtree_end(prev)) {
    return Status::InvalidArgument("octants " + describe_octant(octant_from_key(prev)) + " and " +
                                   describe_octant(octant_from_key(cursor_.key())) + " overlap");
  }
  return Status::Ok();
}

}  // namespace weaver
