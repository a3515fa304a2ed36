// Helpers for the libFuzzer targets: the fuzzer's bytes as a file.
#pragma once

#include <sys/mman.h>
#include <unistd.h>

#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>

#include "storage/file.h"

namespace weaver::fuzz {

// The bytes in an anonymous in-memory file, reachable by path
// (/proc/self/fd/N) for the readers that take one.  Closed at scope exit.
class MemoryPath {
 public:
  MemoryPath(const uint8_t* data, size_t size) : fd_(::memfd_create("weaver-fuzz", 0)) {
    for (size_t done = 0; fd_ >= 0 && done < size;) {
      const ssize_t n = ::write(fd_, data + done, size - done);
      if (n <= 0) break;
      done += static_cast<size_t>(n);
    }
  }
  ~MemoryPath() { ::close(fd_); }
  std::string path() const { return "/proc/self/fd/" + std::to_string(fd_); }

 private:
  int fd_;
};

// Writes the bytes as `name` in a scratch directory made once per process,
// for the readers that open a directory (database, LSM); returns the directory.
inline std::string write_scratch_file(const char* name, const uint8_t* data, size_t size) {
  static const std::string dir = [] {
    std::string tmpl = "/tmp/weaver-fuzz-XXXXXX";
    return std::string(::mkdtemp(tmpl.data()));
  }();
  std::ofstream out(dir + "/" + name, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  return dir;
}

// A read-only File over the fuzzer's bytes.
class MemoryFile final : public File {
 public:
  MemoryFile(const uint8_t* data, size_t size)
      : bytes_(reinterpret_cast<const char*>(data), size) {}
  Status read_at(uint64_t offset, void* buf, size_t n, size_t* done) override {
    *done = offset >= bytes_.size() ? 0 : std::min<uint64_t>(n, bytes_.size() - offset);
    if (*done > 0) std::memcpy(buf, bytes_.data() + offset, *done);
    return Status::Ok();
  }
  Status write_at(uint64_t, const void*, size_t, size_t*) override {
    return Status::IOError("read-only");
  }
  Status sync() override { return Status::Ok(); }
  Status size(uint64_t* out) override {
    *out = bytes_.size();
    return Status::Ok();
  }
  Status truncate(uint64_t) override { return Status::IOError("read-only"); }
  const std::string& name() const override { return name_; }

 private:
  std::string bytes_;
  std::string name_ = "fuzz.bt";
};

}  // namespace weaver::fuzz
