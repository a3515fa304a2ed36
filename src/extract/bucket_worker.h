// One high-level bucket of the two-level bucket sort as a self-contained
// task.  The reader (one thread, in Z-order) gathers the bucket's leaves,
// hands their corners that belong to later buckets to the spill store, and
// takes the bucket's incoming spills: every earlier bucket has already been
// read, so they are complete.  A worker (any thread) then merges the nodal
// pixels in a hash, sorts them and classifies each node.  Tasks are written
// out in Z-order, so the node table is the same whatever the thread count.
#pragma once

#include <cstdint>
#include <vector>

#include "db/leaf_reader.h"
#include "extract/extract.h"
#include "extract/node_classifier.h"
#include "extract/node_hash.h"
#include "extract/spill_store.h"
#include "storage/btree.h"

namespace weaver {

struct Bucketing {
  int level;  // bucket level: edge 2^(20-level)
  int shift;  // bits of a node key below the bucket id
  uint64_t of_key(uint64_t node_key) const { return node_key >> shift; }
};

struct BucketTask {
  uint64_t bucket = 0;
  std::vector<uint64_t> leaf_keys;    // the bucket's leaves, key order
  std::vector<SpillRecord> incoming;  // nodal pixels spilled here by earlier buckets
  std::vector<uint64_t> node_keys;    // result: the bucket's nodes, key order
  std::vector<std::byte> node_kinds;  // result: their NodeKind, one byte each
  ExtractResult counts;               // result: node and kind counts
  Status status;
  bool done = false;  // set by the worker (under the pipeline's lock)
};

// Reads the next bucket from the cursor and the spill store into *task;
// returns false in *more when both are exhausted.
Status read_bucket(LeafReader& cursor, const Bucketing& b, SpillStore& spills, BucketTask* task,
                   bool* more);

class BucketWorker {
 public:
  BucketWorker(BTree& octants, const Bucketing& b) : classifier_(octants), b_(b) {}
  Status run(BucketTask& task);

 private:
  NodeClassifier classifier_;
  Bucketing b_;
  NodeHash hash_;
  std::vector<SpillRecord> sorted_;  // (key, mask) pairs being sorted
};

}  // namespace weaver
