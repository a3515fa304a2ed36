// Streams that are sorted already need no sorter.  A SortedSpool takes
// KeyTags in nondecreasing key order, drops repeated keys (the first tag
// stays), holds them in memory until its buffer fills and then on a scratch
// file, and is read back once, in order.  A KeyTagMerge reads several sorted
// sources as one, in (key, tag) order.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "sort/key_tag.h"
#include "storage/file.h"

namespace weaver {

class SortedSpool : public KeyTagSource {
 public:
  // path: the scratch file, made on the first spill and unlinked at once.
  SortedSpool(std::string path, size_t buffer_bytes);

  // A key below the last one added is an Internal error: the caller's
  // stream was not sorted.
  Status add(const KeyTag& item);
  // Ends input; next() then yields the items from the first.
  Status finish();
  Status next(KeyTag* out, bool* done) override;

  uint64_t size() const { return count_; }
  bool spilled() const { return file_ != nullptr; }

 private:
  Status flush();
  Status refill();

  std::string path_;
  size_t capacity_;
  std::vector<KeyTag> buf_;
  std::unique_ptr<File> file_;
  uint64_t count_ = 0, written_ = 0, read_ = 0;
  size_t pos_ = 0;
  bool has_last_ = false, finished_ = false;
  uint64_t last_key_ = 0;
};

class KeyTagMerge : public KeyTagSource {
 public:
  // The sources must outlive the merge and be ready to read.
  explicit KeyTagMerge(std::vector<KeyTagSource*> sources) : sources_(std::move(sources)) {}
  Status next(KeyTag* out, bool* done) override;

 private:
  Status prime();

  std::vector<KeyTagSource*> sources_;
  std::vector<KeyTag> heads_;
  std::vector<bool> live_;
  bool primed_ = false;
};

}  // namespace weaver
