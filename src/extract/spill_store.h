// Nodal pixels that belong to a later bucket wait here until that bucket is
// read.  Buckets are contiguous ranges of node keys taken in increasing order
// (bucket_worker.h), so each bucket's spills arrive as one run sorted by key,
// and a bucket [start, end) takes the head of every run below `end`: all
// waiting keys are >= start, since earlier buckets took theirs.  A min-heap
// on the runs' first keys finds the runs that have something to give.
//
// Runs live in memory up to a byte cap.  Past it, the largest runs move to
// one spill log in a scratch directory, keeping only their first record in
// memory, and are read back a block at a time as their keys come due.  (One log rather
// than a file per run: thousands of small files cost far more in inode churn
// than the I/O itself.)
#pragma once

#include <cstdint>
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

  // Adds one bucket's spills.  REQUIRES: sorted by key, every key at or past
  // the end of the bucket being read.
  Status add_run(std::vector<SpillRecord> run);
  bool empty() const { return heap_.empty(); }
  // Appends every waiting record with key < end to *out (in no set order).
  Status take_below(uint64_t end, std::vector<SpillRecord>* out);
  // Appends the waiting records with the smallest keys to *out, all those
  // of a key together, until at least `count` more are there or none wait;
  // *end := the smallest key left waiting (UINT64_MAX when none is).
  Status take_first(size_t count, uint64_t* end, std::vector<SpillRecord>* out);

  uint64_t records_added() const { return records_added_; }
  uint64_t records_written() const { return records_written_; }
  uint64_t memory_bytes() const { return memory_bytes_; }

 private:
  struct Run {
    std::vector<SpillRecord> head;  // the records in memory; head[pos] is the first waiting
    size_t pos = 0;
    uint64_t log_offset = 0;  // where the rest of the run starts in the log
    uint64_t in_log = 0;      // records of the run still in the log
    uint64_t first_key() const { return head[pos].key; }
  };
  static bool later(const std::unique_ptr<Run>& a, const std::unique_ptr<Run>& b) {
    return a->first_key() > b->first_key();
  }
  Status take_from(Run& run, uint64_t end, std::vector<SpillRecord>* out);
  Status refill(Run& run, size_t records);
  Status move_to_log(Run& run);
  Status shrink_to_cap();
  void release_consumed(Run& run);

  std::string dir_;
  uint64_t cap_;
  size_t block_records_;  // records read back from the log at a time
  uint64_t memory_bytes_ = 0;
  std::vector<std::unique_ptr<Run>> heap_;  // min-heap on first_key()
  std::unique_ptr<File> log_;               // opened on the first spill to disk
  uint64_t log_bytes_ = 0;
  uint64_t records_added_ = 0, records_written_ = 0;
};

}  // namespace weaver
