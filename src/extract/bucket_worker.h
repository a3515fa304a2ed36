// One high-level bucket of the two-level bucket sort as a self-contained
// task.
//
// A bucket is a run of consecutive leaves in Z-order and owns the node keys
// [start, end): start is its first leaf's Morton code (0 for the first
// bucket), end the next bucket's start.  The nodes past the last leaf (those
// on the root's far faces, whose codes exceed every leaf's: more with every
// level of refinement) come last, in buckets without leaves of at most
// about as many nodes as a bucket of leaves has, the last ending at
// UINT64_MAX: one bucket taking them all held 100 MB more than
// `--memory 64M` at 2 Hz.  Every leaf
// around a node has a Morton code no larger than the node's (Morton order
// grows with each coordinate), so when a bucket is read, every earlier bucket
// has handed it the corners it owns.  Where a bucket ends is the policy's
// choice (BucketPolicy): the paper's aligned octants of one level, or about
// K leaves cut at the best-aligned leaf nearby.
//
// The reader (one thread, in Z-order) gathers the bucket's leaves, hands
// their corners at or past `end` to the spill store as one sorted run, and
// takes the spills below `end`.  A worker (any thread) then merges the nodal
// pixels in a hash and sorts them, merges them with the lattices of the
// bucket's complete blocks of leaves (made in key order, never hashed), and
// classifies each node.  Tasks are written out in Z-order, so the node table
// is the same whatever the thread count.
#pragma once

#include <bit>
#include <cstdint>
#include <vector>

#include "db/leaf_reader.h"
#include "extract/extract.h"
#include "extract/node_classifier.h"
#include "extract/node_pixels.h"
#include "extract/spill_store.h"
#include "schema/octant.h"
#include "storage/btree.h"

namespace weaver {

struct BucketPolicy {
  // >= 0: the paper's buckets, the aligned octants of this level.
  int level = -1;
  // Otherwise: at least this many leaves, up to a quarter more, ending
  // before the leaf whose Morton code has the most trailing zeros (so that
  // buckets are nearly aligned subtrees and spill little).
  uint64_t leaves = 1;
  // The part of the mesh to extract (one rank's, in weaver-mpi): the node
  // keys [start, stop), from the leaf with key first_leaf (Morton code
  // start) to the last leaf below stop.  Corners at or past stop are the
  // next parts' (whose ghost layers hold the leaves: extract_shard), so a
  // part that ends before the table does has no tail.
  uint64_t start = 0, stop = UINT64_MAX;
  uint64_t first_leaf = 0;
  // A part's ghost layer (ghost_layer.h): the leaves of earlier parts
  // around its nodes, sorted; their corners reach it as spills beforehand.
  const std::vector<uint64_t>* ghosts = nullptr;
  // Each worker's classifier's cache of leaves: 2^cache_bits keys.
  int cache_bits = NodeClassifier::kCacheBits;
};

struct BucketTask {
  uint64_t start = 0, end = 0;        // the node keys the bucket owns
  std::vector<uint64_t> leaf_keys;    // the bucket's leaves, key order
  int finest_level = 0;               // of its leaves (0 for none)
  std::vector<SpillRecord> incoming;  // nodal pixels spilled here by earlier buckets
  std::vector<uint64_t> node_keys;    // result: the bucket's nodes, key order
  std::vector<std::byte> node_kinds;  // result: their NodeKind, one byte each
  ExtractResult counts;               // result: node and kind counts
  Status status;
};

// Nodal pixels bound for the spill store, merged by key as they come (a
// bucket's far corners are each shared by up to four of its leaves: merged
// before the sort, a quarter of them are sorted), then handed over as one
// sorted run.
class SpillRun {
 public:
  // Starts a run of keys in [base, bound], each a multiple of 2^zeros;
  // before the first add.  (The zeros let a run's offsets fit a word where
  // its bound is far past its base, as past the end of a bucket that
  // crosses a coarse boundary: a quarter of the 1 Hz basin's runs.)
  void begin(uint64_t base, uint64_t bound, int zeros = 0) {
    pixels_.reset(expected_, base & ~((uint64_t{1} << zeros) - 1), zeros, bound);
  }
  void add(uint64_t key, uint8_t mask) { pixels_.add(key, mask); }
  // What was added since begin, sorted by key, one record a key (its bits
  // ORed), to `spills` as one run.
  Status flush(SpillStore& spills);

 private:
  NodePixels pixels_;
  size_t expected_ = 1024;  // the keys of the last run: the next is sized for them
};

// Cuts the octant table into buckets, in Z-order, and routes their spills.
class BucketReader {
 public:
  BucketReader(LeafReader& cursor, const BucketPolicy& policy, SpillStore& spills)
      : cursor_(cursor), policy_(policy), spills_(spills), next_start_(policy.start) {}

  // The next bucket into *task; false in *more after the last one.
  Status next(BucketTask* task, bool* more);

 private:
  Status gather_aligned(BucketTask* task);
  Status gather_counted(BucketTask* task);
  Status spill_far_corners(const BucketTask& task);
  // A bucket of the nodes past the last leaf (spilled by the buckets that
  // touch the root's far faces).
  Status gather_tail(BucketTask* task);
  // Whether the cursor is at a leaf of this part.
  bool at_leaf() const {
    return cursor_.valid() && octant_key_morton(cursor_.key()) < policy_.stop;
  }
  // Where a bucket whose leaves ran out ends: at the next part's first
  // leaf, or (the table's end) where the last leaf ends.
  uint64_t end_after(const std::vector<uint64_t>& leaves) const;

  LeafReader& cursor_;
  BucketPolicy policy_;
  SpillStore& spills_;
  std::vector<uint64_t> carry_;  // leaves read past the last cut
  SpillRun far_corners_;         // spill_far_corners' run
  uint64_t next_start_ = 0;
};

// The 8 corners of the leaf with this key as node keys, corner k at [k]:
// each axis's bits of the near and the far corner, put together.  Made in
// registers, never read back from `out` (the loop that stepped corners 0-3
// into 4-7 in memory was vectorised, and its 16-byte loads of two 8-byte
// stores waited for them: most of its time).
inline void leaf_corner_keys(uint64_t leaf_key, uint64_t out[8]) {
  constexpr uint64_t x_bits = 0x1249249249249249;
  const int bit = kMaxLevel - octant_key_level(leaf_key);
  const uint64_t m = octant_key_morton(leaf_key);
  const uint64_t x[2] = {m & x_bits, morton_step(m, 0, bit) & x_bits};
  const uint64_t y[2] = {m & x_bits << 1, morton_step(m, 1, bit) & x_bits << 1};
  const uint64_t z[2] = {m & x_bits << 2, morton_step(m, 2, bit) & x_bits << 2};
  for (int k = 0; k < 8; ++k) out[k] = x[k & 1] | y[k >> 1 & 1] | z[k >> 2];
}

class BucketWorker {
 public:
  BucketWorker(BTree& octants, const BucketPolicy& policy)
      : classifier_(octants, policy.cache_bits) {
    if (policy.ghosts != nullptr) classifier_.set_ghosts(policy.ghosts, policy.start);
  }
  Status run(BucketTask& task);

 private:
  // A complete block of 8^j leaves of edge 2^bit from the one with Morton
  // code `first` on.  Its half-open lattice, the (2^j)^3 corners in
  // [first, first + 8^j << 3 bit), are its leaves' near corners, in Morton
  // order at first + (i << 3 bit): they are merged into the sorted nodes
  // as they are made (merge_nodes), not hashed and sorted.
  struct Block {
    uint64_t first = 0;
    int j = 0, bit = 0;
  };
  // Records the complete block of 8^j leaves from `first` on and hashes
  // the corners on its far faces.
  void add_block_lattice(uint64_t first, int j, uint64_t end);

  // The trailing zero bits that every key the bucket hashes has less its
  // start.
  static int common_zeros(const BucketTask& t);
  // The hashed nodes (`sorted`, in key order) and the blocks' lattices
  // merged, classified and written to t.
  template <typename Sorted>
  Status merge_nodes(const Sorted& view, size_t count, BucketTask& t);
  // The kinds of t's nodes, from the masks merge_nodes left in node_kinds.
  Status classify_nodes(BucketTask& t);

  NodeClassifier classifier_;
  NodePixels pixels_;
  std::vector<Block> blocks_;  // the bucket's complete blocks, in key order
};

}  // namespace weaver
