// The octant table in key order, refusing invalid keys and overlapping
// octants as it goes: in key order (preorder) an overlap always shows up
// between neighbours.
#pragma once

#include <cstdint>
#include <vector>

#include "schema/octant.h"
#include "schema/status.h"
#include "storage/btree.h"

namespace weaver {

class LeafReader {
 public:
  // At the first leaf whose key is >= from; payloads decoded too only when
  // asked (a scan of the keys alone is faster).
  Status open(BTree& octants, uint64_t from = 0, bool payloads = false);
  bool valid() const { return cursor_.valid(); }
  uint64_t key() const { return cursor_.key(); }  // REQUIRES: valid()
  // REQUIRES: valid(), opened with payloads.
  const std::byte* payload() const { return cursor_.payload(); }
  Status next();  // REQUIRES: valid()
  // Appends the keys of the leaves from the current one on to *out, each
  // checked as next() checks it, while fewer than `most` are appended and
  // their Morton codes are below `stop`; leaves the reader at the first not
  // taken.  A leaf page's keys at a time, not a call a key.
  Status take(size_t most, uint64_t stop, std::vector<uint64_t>* out);

 private:
  Status check_current();
  Status check_key(uint64_t key) const;
  Status overlap(uint64_t prev, uint64_t key) const;

  BTreeCursor cursor_;
  std::string file_;
};

}  // namespace weaver
