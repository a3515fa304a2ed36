// Files that export writes: built under a temporary name beside the final
// one and renamed into place when complete, so a failed or interrupted
// export leaves no partial file (a character device such as /dev/null is
// written in place, never replaced).  A file is written as sections, each a
// buffered stream from a known offset: binary formats whose arrays have known
// sizes write all of them in one pass over the mesh, and a text header whose
// numbers are known only at the end is written last into space kept for it.
#pragma once

#include <cstdint>
#include <cstring>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "schema/status.h"
#include "storage/file.h"

namespace weaver {

class OutputFile {
 public:
  explicit OutputFile(std::string path);
  ~OutputFile();  // removes the temporary file unless finish() succeeded
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;

  Status open();
  Status write_at(uint64_t offset, const void* data, size_t n);
  // Syncs, and renames the temporary file over the final name.
  Status finish();
  const std::string& path() const { return path_; }

 private:
  std::string path_, tmp_;
  bool in_place_ = false;  // a device: written directly
  std::unique_ptr<File> file_;
};

// A buffered stream into an OutputFile from offset `start` on.
class Section {
 public:
  Section(OutputFile& file, uint64_t start, size_t buffer_bytes = 1 << 20)
      : file_(&file), at_(start), cap_(buffer_bytes) {
    buf_.reserve(cap_);
  }
  Status put(const void* data, size_t n) {
    if (buf_.size() + n > cap_) WEAVER_RETURN_IF_ERROR(flush());
    if (n > cap_) return write_through(data, n);
    const auto* p = static_cast<const char*>(data);
    buf_.insert(buf_.end(), p, p + n);
    return Status::Ok();
  }
  template <typename T>
  Status value(T v) {
    return put(&v, sizeof v);  // little-endian: the only byte order weaver runs on
  }
  Status text(std::string_view s) { return put(s.data(), s.size()); }
  Status flush();
  // The offset of the next byte.
  uint64_t end() const { return at_ + buf_.size(); }

 private:
  Status write_through(const void* data, size_t n);
  OutputFile* file_;
  uint64_t at_;
  size_t cap_;
  std::vector<char> buf_;
};

// A text line assembled field by field (numbers without locale or printf).
class LineBuffer {
 public:
  void field(uint64_t v);
  void field(double v);  // shortest text that reads back to v
  void text(std::string_view s) { s_.append(s); }
  void ch(char c) { s_ += c; }
  Status emit(Section& out) {
    const Status st = out.text(s_);
    s_.clear();
    return st;
  }

 private:
  std::string s_;
};

}  // namespace weaver
