// Out-of-core sort of (key, tag) pairs within a memory budget: buffer, sort,
// spill sorted runs to files in a scratch directory, then merge them.  When
// everything fits in the buffer nothing touches the disk.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "schema/status.h"
#include "storage/file.h"

namespace weaver {

struct KeyTag {
  uint64_t key;
  uint64_t tag;
  friend bool operator<(const KeyTag& a, const KeyTag& b) {
    return a.key != b.key ? a.key < b.key : a.tag < b.tag;
  }
};

class ExternalSorter {
 public:
  // Scratch files go to scratch_dir (created on the first spill, removed by
  // the destructor).  memory_bytes bounds the buffer and the merge buffers.
  ExternalSorter(std::string scratch_dir, uint64_t memory_bytes);
  ~ExternalSorter();

  Status add(const KeyTag& item);
  // Ends input; then next() yields everything in (key, tag) order.
  Status finish();
  // Sets *done when no items remain.
  Status next(KeyTag* out, bool* done);

  uint64_t runs_spilled() const { return runs_.size(); }

 private:
  struct Run {
    std::unique_ptr<File> file;
    uint64_t offset = 0, remaining = 0;
    std::vector<KeyTag> buf;
    size_t pos = 0;
  };
  Status spill();
  Status refill(Run& run);
  void heap_push(size_t source);

  std::string scratch_dir_;
  uint64_t memory_bytes_;
  size_t capacity_;
  std::vector<KeyTag> buffer_;
  size_t buffer_pos_ = 0;  // next unread item of buffer_ during the merge
  std::vector<Run> runs_;
  // Merge heap of (key, tag, source); source == runs_.size() is buffer_.
  struct HeapItem {
    KeyTag item;
    size_t source;
  };
  std::vector<HeapItem> heap_;
  bool finished_ = false;
};

}  // namespace weaver
