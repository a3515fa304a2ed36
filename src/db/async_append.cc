#include "db/async_append.h"

#include <utility>

namespace weaver {
namespace {
constexpr size_t kMaxWaiting = 2;
}  // namespace

AsyncAppender::AsyncAppender(BTree& out, bool own_thread) : out_(out) {
  if (own_thread) thread_ = std::thread([this] { run(); });
}

AsyncAppender::~AsyncAppender() { (void)finish(); }

Status AsyncAppender::append(Batch* batch) {
  if (!thread_.joinable()) {
    if (status_.ok()) status_ = append_now(*batch);
    batch->keys.clear();
    batch->payloads.clear();
    return status_;
  }
  std::unique_lock<std::mutex> lock(mu_);
  changed_.wait(lock, [&] { return waiting_.size() < kMaxWaiting || !status_.ok(); });
  if (!status_.ok()) return status_;
  waiting_.push_back(std::move(*batch));
  if (!spare_.empty()) {
    *batch = std::move(spare_.back());
    spare_.pop_back();
  } else {
    *batch = Batch{};
  }
  batch->keys.clear();
  batch->payloads.clear();
  changed_.notify_all();
  return Status::Ok();
}

Status AsyncAppender::finish() {
  {
    std::unique_lock<std::mutex> lock(mu_);
    closing_ = true;
    changed_.notify_all();
  }
  if (thread_.joinable()) thread_.join();
  std::lock_guard<std::mutex> lock(mu_);
  return status_;
}

void AsyncAppender::run() {
  std::unique_lock<std::mutex> lock(mu_);
  while (true) {
    changed_.wait(lock, [&] { return !waiting_.empty() || closing_; });
    if (waiting_.empty()) return;  // closing, and nothing left
    Batch b = std::move(waiting_.front());
    waiting_.pop_front();
    lock.unlock();
    Status st = status_.ok() ? append_now(b) : Status::Ok();
    lock.lock();
    if (!st.ok() && status_.ok()) status_ = std::move(st);
    spare_.push_back(std::move(b));
    changed_.notify_all();
  }
}

Status AsyncAppender::append_now(Batch& b) {
  return out_.append_batch(b.keys.data(), b.payloads.data(), b.keys.size());
}

}  // namespace weaver
