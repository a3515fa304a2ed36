#include "extract/spill_store.h"

#include <algorithm>
#include <filesystem>

namespace weaver {

SpillStore::SpillStore(std::string scratch_dir, uint64_t memory_cap_bytes)
    : dir_(std::move(scratch_dir)), cap_(memory_cap_bytes) {
  // A run read back from the log keeps one block in memory: small enough
  // that many such runs fit under the cap, large enough for sequential reads.
  block_records_ = std::clamp<size_t>(cap_ / 64 / sizeof(SpillRecord), 64, 4096);
}

SpillStore::~SpillStore() {
  log_.reset();
  std::error_code ec;
  if (records_written_ > 0) std::filesystem::remove_all(dir_, ec);
}

namespace {
// What a run's records hold of the heap: their buffer, used or not.
uint64_t held(const std::vector<SpillRecord>& v) { return v.capacity() * sizeof(SpillRecord); }
}  // namespace

Status SpillStore::add_run(std::vector<SpillRecord> run) {
  if (run.empty()) return Status::Ok();
  records_added_ += run.size();
  memory_bytes_ += held(run);
  auto r = std::make_unique<Run>();
  r->head = std::move(run);
  heap_.push_back(std::move(r));
  std::push_heap(heap_.begin(), heap_.end(), later);
  if (memory_bytes_ > cap_) return shrink_to_cap();
  return Status::Ok();
}

Status SpillStore::take_below(uint64_t end, std::vector<SpillRecord>* out) {
  while (!heap_.empty() && heap_.front()->first_key() < end) {
    std::pop_heap(heap_.begin(), heap_.end(), later);
    std::unique_ptr<Run> run = std::move(heap_.back());
    heap_.pop_back();
    WEAVER_RETURN_IF_ERROR(take_from(*run, end, out));
    if (run->pos < run->head.size()) {
      heap_.push_back(std::move(run));
      std::push_heap(heap_.begin(), heap_.end(), later);
    }
  }
  return Status::Ok();
}

Status SpillStore::take_first(size_t count, uint64_t* end, std::vector<SpillRecord>* out) {
  const size_t enough = out->size() + count;
  while (!heap_.empty() && out->size() < enough) {
    // The smallest key waiting, from every run that has it.
    WEAVER_RETURN_IF_ERROR(take_below(heap_.front()->first_key() + 1, out));
  }
  *end = heap_.empty() ? UINT64_MAX : heap_.front()->first_key();
  return Status::Ok();
}

// Moves the run's records below `end` to *out, reading its log blocks as
// they come due; leaves the run empty or with head[pos] >= end.
Status SpillStore::take_from(Run& run, uint64_t end, std::vector<SpillRecord>* out) {
  while (true) {
    const auto first = run.head.begin() + static_cast<ptrdiff_t>(run.pos);
    const auto stop = std::lower_bound(first, run.head.end(), end,
                                       [](const SpillRecord& r, uint64_t k) { return r.key < k; });
    out->insert(out->end(), first, stop);
    run.pos = static_cast<size_t>(stop - run.head.begin());
    if (run.pos < run.head.size()) break;
    if (run.in_log == 0) break;
    WEAVER_RETURN_IF_ERROR(refill(run, block_records_));
  }
  release_consumed(run);
  return Status::Ok();
}

// Replaces the run's (consumed) head by its next records from the log, up
// to `records`.
Status SpillStore::refill(Run& run, size_t records) {
  memory_bytes_ -= held(run.head);
  const size_t n = static_cast<size_t>(std::min<uint64_t>(run.in_log, records));
  // A new buffer of n: resizing would keep the old one, which for a run
  // just moved to the log is the whole run.
  if (run.head.capacity() == n) {
    run.head.resize(n);
  } else {
    std::vector<SpillRecord>(n).swap(run.head);
  }
  run.pos = 0;
  WEAVER_RETURN_IF_ERROR(
      read_fully(*log_, run.log_offset, run.head.data(), n * sizeof(SpillRecord)));
  run.log_offset += n * sizeof(SpillRecord);
  run.in_log -= n;
  memory_bytes_ += held(run.head);
  return Status::Ok();
}

// Gives back the memory of taken records once they are half the run's head
// (so that each record is moved at most once more on average).
void SpillStore::release_consumed(Run& run) {
  if (run.pos == run.head.size()) {
    memory_bytes_ -= held(run.head);
    std::vector<SpillRecord>().swap(run.head);
    run.pos = 0;
    return;
  }
  if (run.pos * 2 < run.head.size() || run.head.size() < block_records_) return;
  memory_bytes_ -= held(run.head);
  std::vector<SpillRecord>(run.head.begin() + static_cast<ptrdiff_t>(run.pos), run.head.end())
      .swap(run.head);
  memory_bytes_ += held(run.head);
  run.pos = 0;
}

// Writes the run's waiting records to the log and keeps only the first in
// memory (for the heap's order) until the run comes due.
Status SpillStore::move_to_log(Run& run) {
  if (!log_) {
    std::error_code ec;
    std::filesystem::create_directories(dir_, ec);
    if (ec) return Status::IOError("cannot create " + dir_ + ": " + ec.message());
    WEAVER_RETURN_IF_ERROR(open_posix_file(dir_ + "/spill.log", OpenMode::kCreateTruncate, &log_));
  }
  const uint64_t n = run.head.size() - run.pos;
  WEAVER_RETURN_IF_ERROR(
      write_fully(*log_, log_bytes_, run.head.data() + run.pos, n * sizeof(SpillRecord)));
  records_written_ += n;
  run.log_offset = log_bytes_;
  run.in_log = n;
  log_bytes_ += n * sizeof(SpillRecord);
  return refill(run, 1);
}

// Moves the largest runs held in memory to the log until memory is at half
// the cap (or no run has more than one record in memory to give).
Status SpillStore::shrink_to_cap() {
  while (memory_bytes_ > cap_ / 2) {
    Run* largest = nullptr;
    for (auto& r : heap_) {
      if (r->in_log == 0 && r->head.size() - r->pos > 1 &&
          (!largest || r->head.size() - r->pos > largest->head.size() - largest->pos)) {
        largest = r.get();
      }
    }
    if (largest == nullptr) break;
    WEAVER_RETURN_IF_ERROR(move_to_log(*largest));
  }
  return Status::Ok();
}

}  // namespace weaver
