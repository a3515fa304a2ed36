#include "extract/spill_store.h"

#include <algorithm>
#include <filesystem>
#include <memory>

namespace weaver {

SpillStore::SpillStore(std::string scratch_dir, uint64_t memory_cap_bytes)
    : dir_(std::move(scratch_dir)), cap_(memory_cap_bytes) {}

SpillStore::~SpillStore() {
  log_.reset();
  std::error_code ec;
  if (records_written_ > 0) std::filesystem::remove_all(dir_, ec);
}

Status SpillStore::add(uint64_t bucket, const SpillRecord& r) {
  memory_[bucket].push_back(r);
  memory_bytes_ += sizeof(SpillRecord);
  ++records_added_;
  if (memory_bytes_ > cap_) return flush_largest();
  return Status::Ok();
}

uint64_t SpillStore::first_bucket() const {
  uint64_t b = UINT64_MAX;
  if (!memory_.empty()) b = memory_.begin()->first;
  if (!on_disk_.empty()) b = std::min(b, on_disk_.begin()->first);
  return b;
}

// Appends the largest buffers to the log until memory is at half the cap.
Status SpillStore::flush_largest() {
  if (!log_) {
    std::error_code ec;
    std::filesystem::create_directories(dir_, ec);
    if (ec) return Status::IOError("cannot create " + dir_ + ": " + ec.message());
    WEAVER_RETURN_IF_ERROR(open_posix_file(dir_ + "/spill.log", OpenMode::kCreateTruncate, &log_));
  }
  std::vector<std::pair<size_t, uint64_t>> by_size;
  for (const auto& [bucket, recs] : memory_) by_size.push_back({recs.size(), bucket});
  std::sort(by_size.rbegin(), by_size.rend());
  for (const auto& [size, bucket] : by_size) {
    if (memory_bytes_ <= cap_ / 2) break;
    std::vector<SpillRecord>& recs = memory_[bucket];
    const uint64_t bytes = recs.size() * sizeof(SpillRecord);
    WEAVER_RETURN_IF_ERROR(write_fully(*log_, log_bytes_, recs.data(), bytes));
    on_disk_[bucket].push_back({log_bytes_, recs.size()});
    log_bytes_ += bytes;
    records_written_ += recs.size();
    memory_bytes_ -= recs.size() * sizeof(SpillRecord);
    memory_.erase(bucket);
  }
  return Status::Ok();
}

Status SpillStore::take(uint64_t bucket, std::vector<SpillRecord>* out) {
  out->clear();
  auto disk = on_disk_.find(bucket);
  if (disk != on_disk_.end()) {
    for (const Chunk& c : disk->second) {
      const size_t at = out->size();
      out->resize(at + c.count);
      WEAVER_RETURN_IF_ERROR(
          read_fully(*log_, c.offset, out->data() + at, c.count * sizeof(SpillRecord)));
    }
    on_disk_.erase(disk);
  }
  auto mem = memory_.find(bucket);
  if (mem != memory_.end()) {
    out->insert(out->end(), mem->second.begin(), mem->second.end());
    memory_bytes_ -= mem->second.size() * sizeof(SpillRecord);
    memory_.erase(mem);
  }
  return Status::Ok();
}

}  // namespace weaver
