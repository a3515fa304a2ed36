// The file seam: every byte the storage engine reads or writes goes through a
// File.  The engine calls read_fully / write_fully, which loop over partial
// transfers; tests substitute a File that fails, or transfers less than asked.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "schema/status.h"

namespace weaver {

class File {
 public:
  virtual ~File() = default;

  // Like pread/pwrite: transfers at most n bytes at offset, sets *done to the
  // count (0 at end of file for reads), and returns an error only when the
  // system call failed.
  virtual Status read_at(uint64_t offset, void* buf, size_t n, size_t* done) = 0;
  virtual Status write_at(uint64_t offset, const void* buf, size_t n, size_t* done) = 0;
  virtual Status sync() = 0;
  virtual Status size(uint64_t* out) = 0;
  virtual Status truncate(uint64_t size) = 0;
  // The path, for error messages.
  virtual const std::string& name() const = 0;
};

enum class OpenMode { kReadOnly, kReadWrite, kCreateTruncate };

Status open_posix_file(const std::string& path, OpenMode mode, std::unique_ptr<File>* out);
// A descriptor open for reading (O_CLOEXEC), or -1 with errno set.  Without
// access-time updates where the file's owner may ask for that: every read
// of a file opened otherwise asks the kernel whether to update the time.
int open_for_reading(const std::string& path);
// A read-only File over a duplicate of an open descriptor (the original stays
// open): a reader's snapshot survives the file being unlinked by a writer.
Status dup_posix_file(int fd, const std::string& path, std::unique_ptr<File>* out);

// Reads exactly n bytes; a short read (end of file) is Corruption naming the
// file and offset, since every caller expects the bytes to exist.
Status read_fully(File& f, uint64_t offset, void* buf, size_t n);
// Writes exactly n bytes; a write that makes no progress is an IOError.
Status write_fully(File& f, uint64_t offset, const void* buf, size_t n);

}  // namespace weaver
