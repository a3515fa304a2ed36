#include "storage/file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "storage/crash_point.h"

namespace weaver {
namespace {

std::string errno_text(const std::string& what, const std::string& path) {
  return what + " " + path + ": " + std::strerror(errno);
}

class PosixFile final : public File {
 public:
  PosixFile(int fd, std::string path) : fd_(fd), path_(std::move(path)) {}
  ~PosixFile() override {
    crash_point::note_close(fd_);
    ::close(fd_);
  }

  Status read_at(uint64_t offset, void* buf, size_t n, size_t* done) override {
    ssize_t r;
    do {
      r = ::pread(fd_, buf, n, static_cast<off_t>(offset));
    } while (r < 0 && errno == EINTR);
    if (r < 0) return Status::IOError(errno_text("read", path_));
    *done = static_cast<size_t>(r);
    return Status::Ok();
  }

  Status write_at(uint64_t offset, const void* buf, size_t n, size_t* done) override {
    if (const int e = crash_point::step()) return injected("write", e);
    ssize_t r;
    do {
      r = ::pwrite(fd_, buf, n, static_cast<off_t>(offset));
    } while (r < 0 && errno == EINTR);
    if (r < 0) return Status::IOError(errno_text("write", path_));
    crash_point::note_write(fd_, offset, static_cast<size_t>(r));
    *done = static_cast<size_t>(r);
    return Status::Ok();
  }

  Status sync() override {
    if (const int e = crash_point::step()) return injected("sync", e);
    if (::fdatasync(fd_) != 0) return Status::IOError(errno_text("sync", path_));
    crash_point::note_sync(fd_);
    return Status::Ok();
  }

  Status size(uint64_t* out) override {
    struct stat st;
    if (::fstat(fd_, &st) != 0) return Status::IOError(errno_text("stat", path_));
    *out = static_cast<uint64_t>(st.st_size);
    return Status::Ok();
  }

  Status truncate(uint64_t size) override {
    if (::ftruncate(fd_, static_cast<off_t>(size)) != 0) {
      return Status::IOError(errno_text("truncate", path_));
    }
    return Status::Ok();
  }

  const std::string& name() const override { return path_; }

 private:
  Status injected(const char* what, int e) const {
    return Status::IOError(std::string("cannot ") + what + " " + path_ + ": " + std::strerror(e));
  }

  int fd_;
  std::string path_;
};

}  // namespace

int open_for_reading(const std::string& path) {
#ifdef O_NOATIME
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NOATIME);
  if (fd >= 0 || errno != EPERM) return fd;  // EPERM: not the owner's to ask
#endif
  return ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
}

Status open_posix_file(const std::string& path, OpenMode mode, std::unique_ptr<File>* out) {
  int flags = O_CLOEXEC;
  switch (mode) {
    case OpenMode::kReadOnly: flags |= O_RDONLY; break;
    case OpenMode::kReadWrite: flags |= O_RDWR; break;
    case OpenMode::kCreateTruncate: flags |= O_RDWR | O_CREAT | O_TRUNC; break;
  }
  const int fd =
      mode == OpenMode::kReadOnly ? open_for_reading(path) : ::open(path.c_str(), flags, 0644);
  if (fd < 0) return Status::IOError(errno_text("cannot open", path));
  *out = std::make_unique<PosixFile>(fd, path);
  return Status::Ok();
}

Status dup_posix_file(int fd, const std::string& path, std::unique_ptr<File>* out) {
  const int copy = ::fcntl(fd, F_DUPFD_CLOEXEC, 0);
  if (copy < 0) return Status::IOError(errno_text("cannot duplicate descriptor of", path));
  *out = std::make_unique<PosixFile>(copy, path);
  return Status::Ok();
}

Status read_fully(File& f, uint64_t offset, void* buf, size_t n) {
  auto* p = static_cast<char*>(buf);
  while (n > 0) {
    size_t done = 0;
    WEAVER_RETURN_IF_ERROR(f.read_at(offset, p, n, &done));
    if (done == 0) {
      return Status::Corruption(f.name() + ": file is truncated (no data at byte offset " +
                                std::to_string(offset) + ")");
    }
    p += done;
    offset += done;
    n -= done;
  }
  return Status::Ok();
}

Status write_fully(File& f, uint64_t offset, const void* buf, size_t n) {
  const auto* p = static_cast<const char*>(buf);
  while (n > 0) {
    size_t done = 0;
    WEAVER_RETURN_IF_ERROR(f.write_at(offset, p, n, &done));
    if (done == 0) {
      return Status::IOError(f.name() + ": write made no progress at byte offset " +
                             std::to_string(offset));
    }
    p += done;
    offset += done;
    n -= done;
  }
  return Status::Ok();
}

}  // namespace weaver
