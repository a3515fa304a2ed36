#include "extract/spill_store.h"

#include <algorithm>
#include <filesystem>
#include <memory>

#include "storage/file.h"

namespace weaver {

SpillStore::SpillStore(std::string scratch_dir, uint64_t memory_cap_bytes)
    : dir_(std::move(scratch_dir)), cap_(memory_cap_bytes) {}

SpillStore::~SpillStore() {
  std::error_code ec;
  if (records_written_ > 0) std::filesystem::remove_all(dir_, ec);
}

std::string SpillStore::file_of(uint64_t bucket) const {
  return dir_ + "/spill-" + std::to_string(bucket);
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

// Appends the largest buffers to their files until memory is at half the cap.
Status SpillStore::flush_largest() {
  std::error_code ec;
  std::filesystem::create_directories(dir_, ec);
  if (ec) return Status::IOError("cannot create " + dir_ + ": " + ec.message());
  std::vector<std::pair<size_t, uint64_t>> by_size;
  for (const auto& [bucket, recs] : memory_) by_size.push_back({recs.size(), bucket});
  std::sort(by_size.rbegin(), by_size.rend());
  for (const auto& [size, bucket] : by_size) {
    if (memory_bytes_ <= cap_ / 2) break;
    std::vector<SpillRecord>& recs = memory_[bucket];
    std::unique_ptr<File> f;
    const std::string path = file_of(bucket);
    const bool exists = on_disk_.count(bucket) != 0;
    WEAVER_RETURN_IF_ERROR(
        open_posix_file(path, exists ? OpenMode::kReadWrite : OpenMode::kCreateTruncate, &f));
    const uint64_t offset = on_disk_[bucket] * sizeof(SpillRecord);
    WEAVER_RETURN_IF_ERROR(write_fully(*f, offset, recs.data(), recs.size() * sizeof(SpillRecord)));
    on_disk_[bucket] += recs.size();
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
    std::unique_ptr<File> f;
    WEAVER_RETURN_IF_ERROR(open_posix_file(file_of(bucket), OpenMode::kReadOnly, &f));
    out->resize(disk->second);
    WEAVER_RETURN_IF_ERROR(read_fully(*f, 0, out->data(), out->size() * sizeof(SpillRecord)));
    f.reset();
    std::error_code ec;
    std::filesystem::remove(file_of(bucket), ec);
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
