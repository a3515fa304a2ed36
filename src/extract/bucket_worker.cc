#include "extract/bucket_worker.h"

#include <algorithm>
#include <array>
#include <bit>

#include "schema/octant.h"

namespace weaver {

namespace {

// Where the last bucket of leaves ends: where its last leaf does.  Not
// sooner (a bucket's range holds whole leaves: the classifier looks no
// further for a leaf holding a pixel in it), and not later: the nodes past
// it wait for the tail (gather_tail).
uint64_t leaves_end(const std::vector<uint64_t>& leaves) {
  const uint64_t last = leaves.back();
  return octant_key_morton(last) + (uint64_t{1} << (3 * (kMaxLevel - octant_key_level(last))));
}

// The Morton code of corner 7 of the octant at code m with edge 2^bit.
uint64_t far_corner(uint64_t m, int bit) {
  return morton_step(morton_step(morton_step(m, 0, bit), 1, bit), 2, bit);
}

// No corner of these leaves (in key order) has a larger key than this: the
// far corner of the least aligned octant holding them all.
uint64_t corners_bound(const std::vector<uint64_t>& leaves) {
  if (leaves.empty()) return 0;
  const uint64_t first = octant_key_morton(leaves.front());
  const uint64_t last = leaves_end(leaves) - 1;            // the last leaf's last pixel
  const int bit = (std::bit_width(first ^ last) + 2) / 3;  // the octant's edge, 2^bit (<= 20)
  const uint64_t span = (uint64_t{1} << (3 * bit)) - 1;
  return far_corner(first & ~span, bit);
}

// The finest level among these leaves (0 for none).
int finest_leaf_level(const std::vector<uint64_t>& leaves) {
  int finest = 0;
  for (uint64_t key : leaves) finest = std::max(finest, octant_key_level(key));
  return finest;
}

// The first of leaves[from, size) with a key at or past `bound`: steps
// that double from `from`, then a binary search within the last, so a run
// of r leaves costs about 2 log2(r) comparisons, one leaf just one.
size_t first_at_or_past(const std::vector<uint64_t>& leaves, size_t from, uint64_t bound) {
  size_t step = 1, low = from;
  while (low + step < leaves.size() && leaves[low + step] < bound) low += step, step *= 2;
  const auto high = leaves.begin() + static_cast<ptrdiff_t>(std::min(low + step, leaves.size()));
  return static_cast<size_t>(
      std::lower_bound(leaves.begin() + static_cast<ptrdiff_t>(low), high, bound) - leaves.begin());
}

}  // namespace

uint64_t BucketReader::end_after(const std::vector<uint64_t>& leaves) const {
  return cursor_.valid() ? octant_key_morton(cursor_.key()) : leaves_end(leaves);
}

Status BucketReader::next(BucketTask* task, bool* more) {
  const bool leaves_left = at_leaf() || !carry_.empty();
  // A part before the table's end has no tail: its spills left at the end
  // are the later parts' (and reached them before: extract_shard).
  *more = leaves_left || (policy_.stop == UINT64_MAX && !spills_.empty());
  if (!*more) return Status::Ok();
  task->leaf_keys.clear();
  task->finest_level = 0;
  task->incoming.clear();
  task->start = next_start_;
  if (!leaves_left) return gather_tail(task);
  WEAVER_RETURN_IF_ERROR(policy_.level >= 0 ? gather_aligned(task) : gather_counted(task));
  task->finest_level = finest_leaf_level(task->leaf_keys);
  next_start_ = task->end;
  WEAVER_RETURN_IF_ERROR(spills_.take_below(task->end, &task->incoming));
  return spill_far_corners(*task);
}

Status BucketReader::gather_tail(BucketTask* task) {
  // A bucket of K leaves has about 1.5 K nodes (the paper's buckets by
  // level set no K: theirs take 1536).
  const uint64_t nodes = std::max<uint64_t>(policy_.leaves, 1024) * 3 / 2;
  WEAVER_RETURN_IF_ERROR(spills_.take_first(nodes, &task->end, &task->incoming));
  next_start_ = task->end;
  return Status::Ok();
}

// The paper's S2: the leaves under one aligned octant of the policy's level.
Status BucketReader::gather_aligned(BucketTask* task) {
  const int shift = 3 * (kMaxLevel - policy_.level);
  const uint64_t bucket = octant_key_morton(cursor_.key()) >> shift;
  while (at_leaf() && (octant_key_morton(cursor_.key()) >> shift) == bucket) {
    task->leaf_keys.push_back(cursor_.key());
    WEAVER_RETURN_IF_ERROR(cursor_.next());
  }
  task->end = end_after(task->leaf_keys);
  return Status::Ok();
}

// About policy_.leaves leaves: reads a quarter more, then cuts before the
// leaf whose Morton code has the most trailing zeros (the coarsest aligned
// boundary in that window); the leaves past the cut start the next bucket.
Status BucketReader::gather_counted(BucketTask* task) {
  std::vector<uint64_t>& leaves = task->leaf_keys;
  leaves.swap(carry_);
  const size_t want = std::max<uint64_t>(policy_.leaves, 1);
  const size_t window = want + std::max<size_t>(want / 4, 1);
  if (leaves.size() < window) {
    WEAVER_RETURN_IF_ERROR(cursor_.take(window - leaves.size(), policy_.stop, &leaves));
  }
  if (leaves.size() < window) {
    task->end = end_after(leaves);  // the part's (or the table's) last leaves
    return Status::Ok();
  }
  size_t cut = want;
  int best = -1;
  for (size_t i = want; i < leaves.size(); ++i) {
    const int zeros = std::countr_zero(octant_key_morton(leaves[i]));
    if (zeros > best) best = zeros, cut = i;
  }
  carry_.assign(leaves.begin() + static_cast<ptrdiff_t>(cut), leaves.end());
  leaves.resize(cut);
  task->end = octant_key_morton(carry_.front());
  return Status::Ok();
}

// Hands the corners of the bucket's leaves at or past its end to the spill
// store, as one run sorted by key with duplicates merged.
Status BucketReader::spill_far_corners(const BucketTask& task) {
  uint64_t corners[8];
  // Corner 7 has the largest key: below the end, all are.  A Morton code
  // grows with each coordinate, so the far corner of an octant holding the
  // leaf bounds the leaf's: the coarsest ancestor whose far corner is below
  // the end clears every leaf inside it, which (the leaves in key order,
  // none overlapping: LeafReader refuses that) are the next ones up to its
  // subtree's end key, found by a search, not a test of each.
  const std::vector<uint64_t>& leaves = task.leaf_keys;
  far_corners_.begin(task.end, corners_bound(leaves), 3 * (kMaxLevel - task.finest_level));
  for (size_t i = 0; i < leaves.size();) {
    const uint64_t key = leaves[i];
    const uint64_t m = octant_key_morton(key);
    const int bit = kMaxLevel - octant_key_level(key);
    if (far_corner(m, bit) < task.end) {
      int up = bit;
      while (up < kMaxLevel) {
        const uint64_t block = m & ~((uint64_t{1} << (3 * (up + 1))) - 1);
        if (far_corner(block, up + 1) >= task.end) break;
        ++up;
      }
      const uint64_t cleared = up == bit ? key : octant_key_ancestor(key, kMaxLevel - up);
      i = first_at_or_past(leaves, i + 1, octant_key_subtree_end(cleared));
      continue;
    }
    ++i;
    leaf_corner_keys(key, corners);
    for (int c = 0; c < 8; ++c) {
      if (corners[c] >= task.end) far_corners_.add(corners[c], corner_direction_bit(c));
    }
  }
  return far_corners_.flush(spills_);
}

Status SpillRun::flush(SpillStore& spills) {
  // In a buffer of just their size: the spill store holds thousands of runs.
  std::vector<SpillRecord> run(pixels_.size());
  pixels_.sorted([&run](const auto& sorted, size_t count) {
    for (size_t i = 0; i < count; ++i) run[i] = {sorted.key(i), sorted.mask(i)};
  });
  expected_ = std::max<size_t>(run.size(), 1024);
  return spills.add_run(std::move(run));
}

namespace {

// The deepest block made a lattice: 8^4 = 4096 leaves.  A quarter of the
// 2 Hz basin's leaves lie in such blocks; as blocks of 512 they hashed 0.42
// corners a leaf, as blocks of 4096 they hash 0.2 (817 of 4913).  Deeper
// blocks no longer fit a bucket of 8192 leaves once it is cut.
constexpr int kMostBlockDepth = 4;

// The largest j (kMostBlockDepth down to 1) such that the 8^j leaves from `first` on, in
// key order, fill their ancestor j levels up: all of one level, the first
// aligned to that ancestor and the last at its far corner (8^j distinct
// leaves of the level within its range are then all of its cells).  The
// levels matter where leaves need not fill their parents: with holes, finer
// leaves can sit between two of them.  0 when not even 8 siblings do.
int complete_block(const uint64_t* first, size_t left) {
  const int level = octant_key_level(first[0]);
  const int bits = 3 * (kMaxLevel - level);
  const uint64_t m = octant_key_morton(first[0]);
  for (int j = std::min(kMostBlockDepth, level); j >= 1; --j) {
    const size_t count = size_t{1} << (3 * j);
    if (count > left || ((m >> bits) & (count - 1)) != 0) continue;
    const uint64_t last = first[count - 1];
    if (octant_key_level(last) != level || octant_key_morton(last) != m + ((count - 1) << bits)) {
      continue;
    }
    size_t k = 1;
    while (k < count - 1 && octant_key_level(first[k]) == level) ++k;
    if (k == count - 1) return j;
  }
  return 0;
}

// The cells around a lattice point that hold one of the block's leaves, on
// one axis of a block of `side` leaves an edge: at 0 only the + cells (the
// axis's bit set in the direction), at `side` only the - cells, between both.
uint8_t axis_cells(int at, int side, int axis) {
  const uint8_t plus_side = axis == 0 ? 0xAA : axis == 1 ? 0xCC : 0xF0;
  return at == 0 ? plus_side : at == side ? static_cast<uint8_t>(~plus_side) : 0xFF;
}

}  // namespace

// A complete block's corners are (side + 1)^3 points, side = 2^j.  Those
// of its half-open lattice (no coordinate at `side`) are recorded as the
// block and made again, in key order, by merge_nodes; only the corners on
// its far faces are hashed (for 8 leaves 19 of 27; for 4096 leaves 817 of
// 4913), as every corner of a leaf outside a block is.  The corners strictly
// inside the block are anchored and no other leaf has them; those on its
// near faces may be other leaves' corners too (hashed, or spilled here):
// merge_nodes ORs their bits together.
void BucketWorker::add_block_lattice(uint64_t first, int j, uint64_t end) {
  const int bit = kMaxLevel - octant_key_level(first);
  const int side = 1 << j;
  blocks_.push_back({octant_key_morton(first), j, bit});
  auto add = [&](uint64_t key, uint8_t cells) {
    if (key < end) pixels_.add(key, cells);
  };
  uint64_t plane = octant_key_morton(first);
  for (int c = 0; c <= side; ++c, plane = morton_step(plane, 2, bit)) {
    const uint8_t cells_z = axis_cells(c, side, 2);
    uint64_t row = plane;
    for (int b = 0; b <= side; ++b, row = morton_step(row, 1, bit)) {
      const uint8_t cells_yz = cells_z & axis_cells(b, side, 1);
      if (b < side && c < side) {  // only the row's far end is on a far face
        add(morton_step(row, 0, bit + j), cells_yz & axis_cells(side, side, 0));
        continue;
      }
      uint64_t key = row;
      for (int a = 0; a <= side; ++a, key = morton_step(key, 0, bit)) {
        add(key, cells_yz & axis_cells(a, side, 0));
      }
    }
  }
}

// Every key hashed is a corner of a leaf (a multiple of the finest leaf's
// size, as the start is of its own leaf's) or a spilled one.
int BucketWorker::common_zeros(const BucketTask& t) {
  uint64_t differ = t.start;
  for (const SpillRecord& r : t.incoming) differ |= r.key - t.start;
  return std::min(3 * (kMaxLevel - t.finest_level), differ == 0 ? 64 : std::countr_zero(differ));
}

Status BucketWorker::run(BucketTask& t) {
  t.counts = ExtractResult{};
  t.counts.elements = t.leaf_keys.size();
  classifier_.set_local(&t.leaf_keys, t.start, t.end);
  // Up to about 1.5 nodes a leaf (a randomly refined octree's dangling
  // nodes); sized for them, the table never grows mid-bucket.
  const size_t expected = t.leaf_keys.size() * 3 / 2 + t.incoming.size() + 64;
  pixels_.reset(expected, t.start, common_zeros(t), t.end - 1);
  uint64_t corners[8];
  const std::vector<uint64_t>& leaves = t.leaf_keys;
  blocks_.clear();
  for (size_t i = 0; i < leaves.size();) {
    if (const int j = complete_block(&leaves[i], leaves.size() - i)) {
      add_block_lattice(leaves[i], j, t.end);
      i += size_t{1} << (3 * j);
      continue;
    }
    leaf_corner_keys(leaves[i++], corners);
    for (int c = 0; c < 8; ++c) {
      if (corners[c] < t.end) pixels_.add(corners[c], corner_direction_bit(c));
    }
  }
  for (const SpillRecord& r : t.incoming) pixels_.add(r.key, r.mask);
  return pixels_.sorted(
      [&](const auto& sorted, size_t count) { return merge_nodes(sorted, count, t); });
}

namespace {

// The cells of a block's half-open lattice point i (its offset in Morton
// order, < 8^kMostBlockDepth) that the block's leaves fill: on an axis where
// the point is at 0, the + side only.  One table serves every block size:
// for a block of 8^j leaves, i < 8^j has no bits above 3j.
constexpr size_t kBlockPoints = size_t{1} << (3 * kMostBlockDepth);
constexpr std::array<uint8_t, kBlockPoints> near_cells_table() {
  std::array<uint8_t, kBlockPoints> t{};
  constexpr uint64_t x_bits = 0x1249249249249249 & (kBlockPoints - 1);  // every third bit
  for (size_t i = 0; i < kBlockPoints; ++i) {
    uint8_t cells = 0xFF;
    if ((i & x_bits) == 0) cells &= 0xAA;
    if ((i & (x_bits << 1)) == 0) cells &= 0xCC;
    if ((i & (x_bits << 2)) == 0) cells &= 0xF0;
    t[i] = cells;
  }
  return t;
}
constexpr std::array<uint8_t, kBlockPoints> kNearCells = near_cells_table();

}  // namespace

// Both inputs are in key order and the blocks' lattices are disjoint, so one
// pass merges them; a point in both (a near face's corner that an earlier
// leaf or a spill has too) is one node with both masks.  The merge writes
// each node's mask where its kind goes, and a second pass classifies: with
// the classifier's calls in the merge, its counters lived on the stack, and
// each node waited on their stores (a fifth of its samples).
template <typename Sorted>
Status BucketWorker::merge_nodes(const Sorted& view, size_t count, BucketTask& t) {
  const Sorted sorted = view;  // a copy in registers: the masks' byte stores may alias the view
  size_t bound = count;
  for (const Block& b : blocks_) bound += size_t{1} << (3 * b.j);
  t.node_keys.resize(bound);
  t.node_kinds.resize(bound);
  uint64_t* keys = t.node_keys.data();
  auto* masks = reinterpret_cast<uint8_t*>(t.node_kinds.data());
  size_t n = 0, h = 0;
  // The next hashed node's key, UINT64_MAX past the last (no node's).
  auto key_at = [&](size_t i) { return i < count ? sorted.key(i) : UINT64_MAX; };
  uint64_t next = key_at(0);
  for (const Block& b : blocks_) {
    const uint64_t points = uint64_t{1} << (3 * b.j);
    for (uint64_t i = 0; i < points; ++i) {
      const uint64_t key = b.first + (i << (3 * b.bit));
      for (; next < key; next = key_at(++h), ++n) keys[n] = next, masks[n] = sorted.mask(h);
      uint8_t mask = kNearCells[i];
      if (next == key) mask |= sorted.mask(h), next = key_at(++h);
      keys[n] = key, masks[n++] = mask;
    }
  }
  for (; h < count; ++h, ++n) keys[n] = sorted.key(h), masks[n] = sorted.mask(h);
  t.node_keys.resize(n);
  t.node_kinds.resize(n);
  return classify_nodes(t);
}

// Each node's mask (in node_kinds) made its kind: a full mask is anchored
// (most nodes, no call), the classifier decides the rest.
Status BucketWorker::classify_nodes(BucketTask& t) {
  uint64_t dangling[3] = {0, 0, 0};  // by kind (the rest are anchored)
  const size_t n = t.node_keys.size();
  for (size_t i = 0; i < n; ++i) {
    const auto mask = static_cast<uint8_t>(t.node_kinds[i]);
    if (mask == 0xFF) {
      t.node_kinds[i] = static_cast<std::byte>(NodeKind::kAnchored);
      continue;
    }
    NodeKind kind = NodeKind::kAnchored;
    WEAVER_RETURN_IF_ERROR(classifier_.classify(t.node_keys[i], mask, &kind));
    t.node_kinds[i] = static_cast<std::byte>(kind);
    ++dangling[static_cast<int>(kind)];
  }
  t.counts.nodes = n;
  t.counts.edge = dangling[static_cast<int>(NodeKind::kEdge)];
  t.counts.face = dangling[static_cast<int>(NodeKind::kFace)];
  t.counts.anchored = n - t.counts.edge - t.counts.face;
  return Status::Ok();
}

}  // namespace weaver
