#include "sort/external_sort.h"

#include <algorithm>
#include <filesystem>

#include "util/radix_sort.h"

namespace weaver {
namespace {

// Run files are read back in chunks of at least this many items, so that the
// merge makes few, large reads whatever the budget.
constexpr size_t kMinReadItems = 4096;
// An intermediate merge writes its output through a buffer this size.
constexpr size_t kWriteItems = 4 * kMinReadItems;

}  // namespace

void sort_key_tags(std::vector<KeyTag>& items, std::vector<KeyTag>& scratch) {
  radix_sort_by(items, scratch, [](const KeyTag& t) { return t.key; });
  for (size_t i = 0; i < items.size();) {
    size_t j = i + 1;
    while (j < items.size() && items[j].key == items[i].key) ++j;
    if (j - i > 1) std::sort(items.begin() + i, items.begin() + j);
    i = j;
  }
}

ExternalSorter::ExternalSorter(std::string scratch_dir, uint64_t memory_bytes, Repeats repeats,
                               uint64_t expected_items)
    : scratch_dir_(std::move(scratch_dir)), memory_bytes_(memory_bytes), repeats_(repeats) {
  // Half of the budget buffers input; the other half feeds the merge.
  capacity_ = std::max<size_t>(kMinReadItems, memory_bytes / 2 / sizeof(KeyTag));
  max_fan_in_ = std::max<size_t>(2, memory_bytes / 2 / sizeof(KeyTag) / kMinReadItems);
  buffer_.reserve(std::min<uint64_t>(capacity_, std::max<uint64_t>(expected_items, 1)));
}

ExternalSorter::~ExternalSorter() {
  runs_.clear();  // closes the run files
  std::error_code ec;
  if (run_files_ > 0) std::filesystem::remove_all(scratch_dir_, ec);
}

Status ExternalSorter::add(const KeyTag& item) {
  if (buffer_.size() == buffer_.capacity()) {
    // The old buffer and the new one together take at most 1.5 times the
    // buffer's half of the budget: within it (the merge half is idle).
    if (buffer_.size() >= capacity_) {
      WEAVER_RETURN_IF_ERROR(spill());
    } else {
      buffer_.reserve(std::min(capacity_, 2 * buffer_.size() + 1024));
    }
  }
  buffer_.push_back(item);
  return Status::Ok();
}

Status ExternalSorter::open_run(Run* run) {
  std::error_code ec;
  std::filesystem::create_directories(scratch_dir_, ec);
  if (ec) return Status::IOError("cannot create " + scratch_dir_ + ": " + ec.message());
  const std::string path = scratch_dir_ + "/run-" + std::to_string(run_files_++);
  WEAVER_RETURN_IF_ERROR(open_posix_file(path, OpenMode::kCreateTruncate, &run->file));
  // The name can go at once: the open descriptor keeps the data.
  std::filesystem::remove(path, ec);
  return Status::Ok();
}

void ExternalSorter::sort_buffer() {
  sort_key_tags(buffer_, scratch_);
  if (repeats_ == Repeats::kFirstOnly) {
    buffer_.erase(std::unique(buffer_.begin(), buffer_.end(),
                              [](const KeyTag& a, const KeyTag& b) { return a.key == b.key; }),
                  buffer_.end());
  }
}

Status ExternalSorter::spill() {
  sort_buffer();
  Run run;
  WEAVER_RETURN_IF_ERROR(open_run(&run));
  WEAVER_RETURN_IF_ERROR(
      write_fully(*run.file, 0, buffer_.data(), buffer_.size() * sizeof(KeyTag)));
  run.remaining = buffer_.size();
  runs_.push_back(std::move(run));
  ++runs_spilled_;
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
                 [](const HeapItem& a, const HeapItem& b) { return b.item < a.item; });
}

// Pops the least item of the heap and pushes its source's next one.
Status ExternalSorter::pop(KeyTag* out) {
  std::pop_heap(heap_.begin(), heap_.end(),
                [](const HeapItem& a, const HeapItem& b) { return b.item < a.item; });
  const HeapItem top = heap_.back();
  heap_.pop_back();
  *out = top.item;
  if (top.source == runs_.size()) {
    if (++buffer_pos_ < buffer_.size()) heap_push(top.source);
    return Status::Ok();
  }
  Run& run = runs_[top.source];
  if (++run.pos == run.buf.size()) {
    if (run.remaining == 0) {
      run.buf = {};
      return Status::Ok();
    }
    WEAVER_RETURN_IF_ERROR(refill(run));
  }
  heap_push(top.source);
  return Status::Ok();
}

// The runs of the prefix become the only runs while they merge (refill then
// splits the merge half of the budget among them), and the result joins the
// rest at the end.
Status ExternalSorter::merge_prefix(size_t count) {
  std::vector<Run> rest(std::make_move_iterator(runs_.begin() + count),
                        std::make_move_iterator(runs_.end()));
  runs_.resize(count);
  const size_t saved_pos = buffer_pos_;
  buffer_pos_ = buffer_.size();  // the in-memory buffer sits this merge out
  heap_.clear();
  for (size_t r = 0; r < count; ++r) {
    WEAVER_RETURN_IF_ERROR(refill(runs_[r]));
    heap_push(r);
  }
  Run merged;
  WEAVER_RETURN_IF_ERROR(open_run(&merged));
  std::vector<KeyTag> out;
  out.reserve(kWriteItems);
  uint64_t written = 0;
  while (!heap_.empty()) {
    out.emplace_back();
    WEAVER_RETURN_IF_ERROR(pop(&out.back()));
    if (out.size() == kWriteItems || heap_.empty()) {
      WEAVER_RETURN_IF_ERROR(write_fully(*merged.file, written * sizeof(KeyTag), out.data(),
                                         out.size() * sizeof(KeyTag)));
      written += out.size();
      out.clear();
    }
  }
  merged.remaining = written;
  runs_ = std::move(rest);
  runs_.push_back(std::move(merged));
  buffer_pos_ = saved_pos;
  return Status::Ok();
}

Status ExternalSorter::finish() {
  finished_ = true;
  sort_buffer();
  scratch_ = {};  // the merge's half of the budget from here on
  if (runs_.empty()) return Status::Ok();
  // Each pass merges just enough runs that the rest fit the fan-in.
  while (runs_.size() > max_fan_in_) {
    WEAVER_RETURN_IF_ERROR(merge_prefix(std::min(max_fan_in_, runs_.size() - max_fan_in_ + 1)));
  }
  // The last buffer (at most half the budget) stays in memory as one more
  // merge source; the run buffers share the other half.
  heap_.clear();
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
  return pop(out);
}

}  // namespace weaver
