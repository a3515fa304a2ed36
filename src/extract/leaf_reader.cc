#include "extract/leaf_reader.h"

#include "extract/node_classifier.h"

namespace weaver {

Status LeafReader::open(BTree& octants) {
  file_ = octants.file_name();
  WEAVER_RETURN_IF_ERROR(octants.seek_cursor(0, &cursor_));
  return cursor_.valid() ? check_current() : Status::Ok();
}

Status LeafReader::check_current() {
  if (!octant_key_is_valid(cursor_.key())) {
    return Status::Corruption(file_ + ": invalid octant key " + std::to_string(cursor_.key()));
  }
  return Status::Ok();
}

Status LeafReader::next() {
  const Octant prev = octant_from_key(cursor_.key());
  WEAVER_RETURN_IF_ERROR(cursor_.next());
  if (!cursor_.valid()) return Status::Ok();
  WEAVER_RETURN_IF_ERROR(check_current());
  const Octant cur = octant_from_key(cursor_.key());
  if (octant_is_ancestor(prev, cur)) {
    return Status::InvalidArgument("octants " + describe_octant(prev) + " and " +
                                   describe_octant(cur) + " overlap");
  }
  return Status::Ok();
}

}  // namespace weaver
