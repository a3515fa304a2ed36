#include "sort/sorted_spool.h"

#include <algorithm>
#include <filesystem>

namespace weaver {

SortedSpool::SortedSpool(std::string path, size_t buffer_bytes)
    : path_(std::move(path)), capacity_(std::max<size_t>(256, buffer_bytes / sizeof(KeyTag))) {}

Status SortedSpool::add(const KeyTag& item) {
  if (has_last_ && item.key <= last_key_) {
    if (item.key == last_key_) return Status::Ok();
    return Status::Internal("sorted spool " + path_ + ": key " + std::to_string(item.key) +
                            " after " + std::to_string(last_key_));
  }
  has_last_ = true;
  last_key_ = item.key;
  if (buf_.size() == capacity_) WEAVER_RETURN_IF_ERROR(flush());
  if (buf_.capacity() == 0) buf_.reserve(capacity_);
  buf_.push_back(item);
  ++count_;
  return Status::Ok();
}

Status SortedSpool::flush() {
  if (file_ == nullptr) {
    std::error_code ec;
    std::filesystem::create_directories(std::filesystem::path(path_).parent_path(), ec);
    WEAVER_RETURN_IF_ERROR(open_posix_file(path_, OpenMode::kCreateTruncate, &file_));
    std::filesystem::remove(path_, ec);  // the descriptor keeps the data
  }
  WEAVER_RETURN_IF_ERROR(
      write_fully(*file_, written_ * sizeof(KeyTag), buf_.data(), buf_.size() * sizeof(KeyTag)));
  written_ += buf_.size();
  buf_.clear();
  return Status::Ok();
}

Status SortedSpool::finish() {
  finished_ = true;
  if (file_ != nullptr && !buf_.empty()) WEAVER_RETURN_IF_ERROR(flush());
  if (file_ != nullptr) buf_.clear();
  pos_ = 0;
  return Status::Ok();
}

Status SortedSpool::refill() {
  const size_t n = static_cast<size_t>(std::min<uint64_t>(capacity_, written_ - read_));
  buf_.resize(n);
  pos_ = 0;
  WEAVER_RETURN_IF_ERROR(
      read_fully(*file_, read_ * sizeof(KeyTag), buf_.data(), n * sizeof(KeyTag)));
  read_ += n;
  return Status::Ok();
}

Status SortedSpool::next(KeyTag* out, bool* done) {
  if (!finished_) return Status::Internal("sorted spool " + path_ + " read before finish");
  if (pos_ == buf_.size()) {
    if (file_ == nullptr || read_ == written_) {
      *done = true;
      buf_ = {};
      return Status::Ok();
    }
    WEAVER_RETURN_IF_ERROR(refill());
  }
  *done = false;
  *out = buf_[pos_++];
  return Status::Ok();
}

Status KeyTagMerge::prime() {
  primed_ = true;
  heads_.resize(sources_.size());
  live_.assign(sources_.size(), false);
  for (size_t i = 0; i < sources_.size(); ++i) {
    bool done = false;
    WEAVER_RETURN_IF_ERROR(sources_[i]->next(&heads_[i], &done));
    live_[i] = !done;
  }
  return Status::Ok();
}

// A linear scan of the heads: merges here join a handful of sources.
Status KeyTagMerge::next(KeyTag* out, bool* done) {
  if (!primed_) WEAVER_RETURN_IF_ERROR(prime());
  size_t best = sources_.size();
  for (size_t i = 0; i < sources_.size(); ++i) {
    if (live_[i] && (best == sources_.size() || heads_[i] < heads_[best])) best = i;
  }
  *done = best == sources_.size();
  if (*done) return Status::Ok();
  *out = heads_[best];
  bool ended = false;
  WEAVER_RETURN_IF_ERROR(sources_[best]->next(&heads_[best], &ended));
  live_[best] = !ended;
  return Status::Ok();
}

}  // namespace weaver
