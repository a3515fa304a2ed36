// Appends batches of records to a table on a thread of its own, so that
// encoding and writing pages overlaps with the work that makes the records
// (balance's refinement: reading, merging and splitting leaves, and the
// material of new leaves).  Batches are appended in the order given: the
// table is the one a plain sorted append builds.  At most two batches wait,
// so memory stays two batches.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <mutex>
#include <thread>
#include <vector>

#include "schema/status.h"
#include "storage/btree.h"

namespace weaver {

class AsyncAppender {
 public:
  struct Batch {
    std::vector<uint64_t> keys;
    std::vector<std::byte> payloads;  // payload_size bytes a key
  };

  // `out` is used only by the appender's thread until finish() returns.
  // Without a thread of its own (own_thread false: a caller given one
  // thread), append() appends the batch before it returns.
  explicit AsyncAppender(BTree& out, bool own_thread = true);
  ~AsyncAppender();  // finishes if finish() was not called
  AsyncAppender(const AsyncAppender&) = delete;
  AsyncAppender& operator=(const AsyncAppender&) = delete;

  // Hands *batch over and gives back an empty one (its buffers recycled).
  // Returns the first error of an earlier append, if any.
  Status append(Batch* batch);
  // Waits until every batch is appended; the first error, if any.
  Status finish();

 private:
  void run();
  Status append_now(Batch& b);

  BTree& out_;
  std::mutex mu_;
  std::condition_variable changed_;
  std::deque<Batch> waiting_;
  std::vector<Batch> spare_;
  bool closing_ = false;
  Status status_;
  std::thread thread_;
};

}  // namespace weaver
