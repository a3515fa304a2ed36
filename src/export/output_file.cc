#include "export/output_file.h"

#include <sys/stat.h>

#include <cerrno>
#include <charconv>
#include <cstdio>

namespace weaver {

OutputFile::OutputFile(std::string path) : path_(std::move(path)), tmp_(path_ + ".tmp") {
  struct stat st;
  in_place_ = ::stat(path_.c_str(), &st) == 0 && S_ISCHR(st.st_mode);
}

OutputFile::~OutputFile() {
  if (file_ != nullptr && !in_place_) {
    file_.reset();
    std::remove(tmp_.c_str());
  }
}

Status OutputFile::open() {
  const std::string& name = in_place_ ? path_ : tmp_;
  const OpenMode mode = in_place_ ? OpenMode::kReadWrite : OpenMode::kCreateTruncate;
  return open_posix_file(name, mode, &file_);
}

Status OutputFile::write_at(uint64_t offset, const void* data, size_t n) {
  return write_fully(*file_, offset, data, n);
}

Status OutputFile::finish() {
  if (in_place_) {
    file_.reset();
    return Status::Ok();
  }
  WEAVER_RETURN_IF_ERROR(file_->sync());
  file_.reset();
  if (std::rename(tmp_.c_str(), path_.c_str()) != 0) {
    const std::string why = std::strerror(errno);
    std::remove(tmp_.c_str());
    return Status::IOError("cannot rename " + tmp_ + " to " + path_ + ": " + why);
  }
  return Status::Ok();
}

Status Section::flush() {
  if (buf_.empty()) return Status::Ok();
  WEAVER_RETURN_IF_ERROR(file_->write_at(at_, buf_.data(), buf_.size()));
  at_ += buf_.size();
  buf_.clear();
  return Status::Ok();
}

Status Section::write_through(const void* data, size_t n) {
  WEAVER_RETURN_IF_ERROR(file_->write_at(at_, data, n));
  at_ += n;
  return Status::Ok();
}

void LineBuffer::field(uint64_t v) {
  char b[24];
  s_.append(b, std::to_chars(b, b + sizeof b, v).ptr);
}

void LineBuffer::field(double v) {
  char b[32];
  s_.append(b, std::to_chars(b, b + sizeof b, v).ptr);
}

}  // namespace weaver
