#include "serve/outbox.h"

#include <fcntl.h>
#include <sys/sendfile.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>

namespace weaver::serve {
namespace {

// A file no name points to, in dir: gone when closed, whatever happens.
int anonymous_file(const std::string& dir) {
  int fd = ::open(dir.c_str(), O_TMPFILE | O_RDWR | O_CLOEXEC, 0600);
  if (fd >= 0) return fd;
  std::string name = dir + "/tmp-serve-spill-XXXXXX";
  fd = ::mkostemp(name.data(), O_CLOEXEC);
  if (fd >= 0) ::unlink(name.c_str());
  return fd;
}

bool write_all(int fd, std::string_view data, uint64_t at) {
  while (!data.empty()) {
    const ssize_t n = ::pwrite(fd, data.data(), data.size(), off_t(at));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    data.remove_prefix(size_t(n)), at += uint64_t(n);
  }
  return true;
}

}  // namespace

FileBody::~FileBody() {
  if (fd >= 0) ::close(fd);
}

bool Outbox::add(std::string_view data, SpillRoom* room) {
  if (data.empty()) return true;
  if (!file_ && bytes_.size() - at_ + data.size() <= kHeldBytes) {
    if (at_ == bytes_.size()) bytes_.clear(), at_ = 0;
    bytes_.append(data);
    return true;
  }
  if (room == nullptr) return false;
  if (room->used.fetch_add(data.size()) + data.size() > room->limit) {
    room->used -= data.size();
    return false;
  }
  if (!file_) {
    const int fd = anonymous_file(room->dir);
    if (fd < 0) return room->used -= data.size(), false;
    file_ = std::make_shared<FileBody>(fd, 0);
    off_ = 0, spill_ = room;
  }
  if (spill_ != room || !write_all(file_->fd, data, file_->size)) {
    room->used -= data.size();
    return false;
  }
  file_->size += data.size();
  return true;
}

bool Outbox::send_some(int fd, uint64_t* sent) {
  while (at_ < bytes_.size()) {
    const ssize_t n = ::send(fd, bytes_.data() + at_, bytes_.size() - at_, MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) return true;
    if (n <= 0) return false;
    at_ += size_t(n), *sent += uint64_t(n);
  }
  bytes_.clear(), at_ = 0;
  while (file_ && off_ < file_->size) {
    off_t at = off_t(off_);
    const ssize_t n = ::sendfile(fd, file_->fd, &at, size_t(file_->size - off_));
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) return true;
    if (n <= 0) return false;
    off_ += uint64_t(n), *sent += uint64_t(n);
  }
  // Sent whole: an export's file is done with, and a spill file too (what
  // comes next is held in memory again, until the client falls behind).
  if (file_) release();
  return true;
}

void Outbox::release() {
  if (spill_ != nullptr && file_) spill_->used -= file_->size;
  file_.reset();
  spill_ = nullptr;
  bytes_.clear(), at_ = 0, off_ = 0;
}

}  // namespace weaver::serve
