// Nodal pixels that fall into a later (inactive) high-level bucket wait here
// until that bucket becomes active: in memory up to a byte cap, beyond which
// the largest per-bucket buffers are appended, as chunks, to one spill log in
// a scratch directory.  An in-memory index lists each bucket's chunks.  (One
// log rather than a file per bucket: thousands of small files cost far more
// in inode churn than the I/O itself.)
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "schema/status.h"
#include "storage/file.h"

namespace weaver {

struct SpillRecord {
  uint64_t key;  // node key
  uint8_t mask;  // direction bits contributed
};

class SpillStore {
 public:
  SpillStore(std::string scratch_dir, uint64_t memory_cap_bytes);
  ~SpillStore();

  Status add(uint64_t bucket, const SpillRecord& r);
  bool empty() const { return memory_.empty() && on_disk_.empty(); }
  // The smallest bucket with waiting records.  REQUIRES: !empty().
  uint64_t first_bucket() const;
  // Moves the bucket's records (from memory and disk) into *out.
  Status take(uint64_t bucket, std::vector<SpillRecord>* out);

  uint64_t records_added() const { return records_added_; }
  uint64_t records_written() const { return records_written_; }

 private:
  struct Chunk {
    uint64_t offset;  // bytes into the log
    uint64_t count;   // records
  };
  Status flush_largest();

  std::string dir_;
  uint64_t cap_;
  uint64_t memory_bytes_ = 0;
  std::map<uint64_t, std::vector<SpillRecord>> memory_;
  std::unique_ptr<File> log_;  // opened on the first flush
  uint64_t log_bytes_ = 0;
  std::map<uint64_t, std::vector<Chunk>> on_disk_;  // bucket -> its chunks in the log
  uint64_t records_added_ = 0, records_written_ = 0;
};

}  // namespace weaver
