#include "import/external_sort.h"

#include <algorithm>
#include <filesystem>

namespace weaver {
namespace {

// Run files are read back in chunks of at least this many items, so that the
// merge makes few, large reads whatever the budget.
constexpr size_t kMinReadItems = 4096;

bool heap_greater(const KeyTag& a, const KeyTag& b) { return b < a; }

}  // namespace

ExternalSorter::ExternalSorter(std::string scratch_dir, uint64_t memory_bytes)
    : scratch_dir_(std::move(scratch_dir)), memory_bytes_(memory_bytes) {
  // Half of the budget buffers input; the other half feeds the merge.
  capacity_ = std::max<size_t>(kMinReadItems, memory_bytes / 2 / sizeof(KeyTag));
  buffer_.reserve(capacity_);
}

ExternalSorter::~ExternalSorter() {
  const bool spilled = !runs_.empty();
  runs_.clear();  // closes the run files
  std::error_code ec;
  if (spilled) std::filesystem::remove_all(scratch_dir_, ec);
}

Status ExternalSorter::add(const KeyTag& item) {
  if (buffer_.size() == capacity_) WEAVER_RETURN_IF_ERROR(spill());
  buffer_.push_back(item);
  return Status::Ok();
}

Status ExternalSorter::spill() {
  std::sort(buffer_.begin(), buffer_.end());
  std::error_code ec;
  std::filesystem::create_directories(scratch_dir_, ec);
  if (ec) return Status::IOError("cannot create " + scratch_dir_ + ": " + ec.message());
  Run run;
  const std::string path = scratch_dir_ + "/run-" + std::to_string(runs_.size());
  WEAVER_RETURN_IF_ERROR(open_posix_file(path, OpenMode::kCreateTruncate, &run.file));
  WEAVER_RETURN_IF_ERROR(
      write_fully(*run.file, 0, buffer_.data(), buffer_.size() * sizeof(KeyTag)));
  run.remaining = buffer_.size();
  runs_.push_back(std::move(run));
  buffer_.clear();
  return Status::Ok();
}

Status ExternalSorter::refill(Run& run) {
  const size_t per_run =
      std::max<size_t>(kMinReadItems, memory_bytes_ / 2 / sizeof(KeyTag) / (runs_.size() + 1));
  const size_t n = static_cast<size_t>(std::min<uint64_t>(per_run, run.remaining));
  run.buf.resize(n);
  run.pos = 0;
  WEAVER_RETURN_IF_ERROR(read_fully(*run.file, run.offset, run.buf.data(), n * sizeof(KeyTag)));
  run.offset += n * sizeof(KeyTag);
  run.remaining -= n;
  return Status::Ok();
}

void ExternalSorter::heap_push(size_t source) {
  const KeyTag& item =
      source == runs_.size() ? buffer_[buffer_pos_] : runs_[source].buf[runs_[source].pos];
  heap_.push_back({item, source});
  std::push_heap(heap_.begin(), heap_.end(),
                 [](const HeapItem& a, const HeapItem& b) { return heap_greater(a.item, b.item); });
}

Status ExternalSorter::finish() {
  finished_ = true;
  std::sort(buffer_.begin(), buffer_.end());
  if (runs_.empty()) return Status::Ok();
  // The last buffer (at most half the budget) stays in memory as one more
  // merge source; the run buffers share the other half.
  for (size_t r = 0; r < runs_.size(); ++r) {
    WEAVER_RETURN_IF_ERROR(refill(runs_[r]));
    heap_push(r);
  }
  if (!buffer_.empty()) heap_push(runs_.size());
  return Status::Ok();
}

Status ExternalSorter::next(KeyTag* out, bool* done) {
  if (runs_.empty()) {  // everything fit in memory
    *done = buffer_pos_ == buffer_.size();
    if (!*done) *out = buffer_[buffer_pos_++];
    return Status::Ok();
  }
  *done = heap_.empty();
  if (*done) return Status::Ok();
  const auto cmp = [](const HeapItem& a, const HeapItem& b) {
    return heap_greater(a.item, b.item);
  };
  std::pop_heap(heap_.begin(), heap_.end(), cmp);
  const HeapItem top = heap_.back();
  heap_.pop_back();
  *out = top.item;
  if (top.source == runs_.size()) {
    if (++buffer_pos_ < buffer_.size()) heap_push(top.source);
    return Status::Ok();
  }
  Run& run = runs_[top.source];
  if (++run.pos == run.buf.size()) {
    if (run.remaining == 0) return Status::Ok();
    WEAVER_RETURN_IF_ERROR(refill(run));
  }
  heap_push(top.source);
  return Status::Ok();
}

}  // namespace weaver
