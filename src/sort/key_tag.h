// A sort record: a 64-bit key and a tag that rides along (a line number, the
// leaf that asked for an octant).  Streams of KeyTags are read through
// KeyTagSource, whatever holds them: a sorter, a spool, a merge of those.
#pragma once

#include <cstdint>

#include "schema/status.h"

namespace weaver {

struct KeyTag {
  uint64_t key;
  uint64_t tag;
  friend bool operator<(const KeyTag& a, const KeyTag& b) {
    return a.key != b.key ? a.key < b.key : a.tag < b.tag;
  }
};

class KeyTagSource {
 public:
  virtual ~KeyTagSource() = default;
  // The next item in order; sets *done (and leaves *out alone) at the end.
  virtual Status next(KeyTag* out, bool* done) = 0;
};

}  // namespace weaver
