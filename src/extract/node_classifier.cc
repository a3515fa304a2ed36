#include "extract/node_classifier.h"

#include <algorithm>
#include <array>
#include <bit>

#include "storage/packed_leaf.h"

namespace weaver {
namespace {

// The Morton code of the pixel next to the node with code m in direction d
// (bit a set: the + side on axis a), without decoding.  False if it lies
// outside the root.
bool direction_pixel(uint64_t m, int d, uint64_t* pixel) {
  for (int a = 0; a < 3; ++a) {
    if ((d >> a) & 1) {
      if ((m >> (3 * kMaxLevel + a)) & 1) return false;  // the node is on the root's far side
    } else {
      if ((m & (0x1249249249249249ULL << a)) == 0) return false;  // on the near side
      m = morton_step_back(m, a, 0);
    }
  }
  *pixel = m;
  return true;
}

// The last key <= k in sorted `keys`, or null.  Branch-free halving: the
// bucket's leaves are searched for millions of nodes, and a mispredicted
// branch at every step of std::upper_bound costs more than the compares.
// The last of keys[0, n) that is <= k, or null.
const uint64_t* last_at_most(const uint64_t* keys, size_t n, uint64_t k) {
  if (n == 0 || keys[0] > k) return nullptr;
  const uint64_t* base = keys;
  while (n > 1) {
    const size_t half = n / 2;
    base = base[half] <= k ? base + half : base;
    n -= half;
  }
  return base;
}

}  // namespace

void NodeClassifier::set_local(const std::vector<uint64_t>* leaf_keys, uint64_t start,
                               uint64_t end) {
  leaf_keys_ = leaf_keys;
  local_start_ = start;
  local_end_ = end;
  local_cached_ = false;
}

// The leaf holding pixel pm, if any: the active bucket's leaves' if pm is
// in its range (no other leaf can hold it), else the ghosts' if pm is before
// a rank's part, else the octant table's.  Works on Morton codes: a leaf
// holds pm iff pm's code is in its subtree's code range.  A bucket's leaves
// go into the cache on its first search, not before: a bucket of one level
// (all its nodes anchored but on the domain's surface) makes none.
Status NodeClassifier::search_leaf(uint64_t pm, const LeafCode** leaf, bool* found) {
  ++searches_;
  const uint64_t pk = pixel_key_of_morton(pm);
  auto holds_p = [pm](uint64_t key) {
    const int bits = 3 * (kMaxLevel - octant_key_level(key));
    return ((octant_key_morton(key) ^ pm) >> bits) == 0;
  };
  *found = false;
  uint64_t key = 0;
  if (leaf_keys_ != nullptr && pm >= local_start_ && pm < local_end_) {
    if (!local_cached_) {
      for (uint64_t k : *leaf_keys_) remember(k);
      local_cached_ = true;
    }
    const uint64_t* floor = last_at_most(leaf_keys_->data(), leaf_keys_->size(), pk);
    if (floor == nullptr || !holds_p(*floor)) return Status::Ok();
    key = *floor;
  } else if (ghosts_ != nullptr && pm < ghosts_below_) {
    const uint64_t* floor = last_at_most(ghosts_->data(), ghosts_->size(), pk);
    if (floor == nullptr || !holds_p(*floor)) return Status::Ok();
    key = *floor;
  } else {
    bool hit = false;
    WEAVER_RETURN_IF_ERROR(table_floor(pk, &key, &hit));
    if (!hit || !holds_p(key)) return Status::Ok();
  }
  remember(key);
  handed_ = {octant_key_morton(key), 3 * (kMaxLevel - octant_key_level(key)), key};
  *leaf = &handed_;
  *found = true;
  return Status::Ok();
}

Status NodeClassifier::table_floor(uint64_t pk, uint64_t* key, bool* hit) {
  static_assert(sizeof(TableBlock::keys) / 8 == page::kPackedBlock);
  const TableBlock* found = nullptr;
  for (const TableBlock& b : table_blocks_) {
    if (pk >= b.lo && pk < b.limit) found = &b;
  }
  if (found == nullptr) {
    TableBlock& b = table_blocks_[next_table_block_];
    b.lo = UINT64_MAX;  // empty until filled
    WEAVER_RETURN_IF_ERROR(octants_.floor_block(pk, b.keys, &b.count, &b.limit));
    // The floor in an earlier leaf, or a table not packed: no block.
    if (b.count == 0) return octants_.floor(pk, key, nullptr, hit);
    b.lo = b.keys[0];
    next_table_block_ = (next_table_block_ + 1) % kTableBlocks;
    found = &b;
  }
  *key = *last_at_most(found->keys, found->count, pk);
  *hit = true;
  return Status::Ok();
}

namespace {

// The cells around a node that a leaf with the node on its closure covers,
// by the axes on which the node is strictly inside the leaf (bits 0-2) and
// those on which it is on the leaf's far face (bits 3-5): both sides of an
// inside axis, the - side of a far one, the + side of the rest.
constexpr std::array<uint8_t, 64> covered_cells_table() {
  std::array<uint8_t, 64> t{};
  for (int i = 0; i < 64; ++i) {
    uint8_t cells = 0xFF;
    for (int a = 0; a < 3; ++a) {
      const uint8_t plus_side = a == 0 ? 0xAA : a == 1 ? 0xCC : 0xF0;  // cells with bit a set
      if ((i >> a) & 1) continue;
      cells &= (i >> (3 + a)) & 1 ? static_cast<uint8_t>(~plus_side) : plus_side;
    }
    t[i] = cells;
  }
  return t;
}
constexpr std::array<uint8_t, 64> kCoveredCells = covered_cells_table();

}  // namespace

// Node m lies on the closure of `leaf`: its kind, and the cells around m the
// leaf covers (on an axis where m is strictly inside the leaf, both sides;
// elsewhere the side the leaf is on).  Read from the codes, all axes at
// once (the leaf's code is zero below span_bits, s): m's coordinate on an
// axis is the leaf's (near face), the leaf's plus less than its edge
// (inside), or plus its edge (far face, which flips the axis's bit at
// s + a and leaves those below it zero).  So the bits of m ^ leaf below s
// are the inside axes' offsets, which at an edge's midpoint or a face's
// centre are exactly their bits at s - 3 + a; the bits at s + a mark the
// far axes.  A verdict, not a Status: the caller makes one only for an
// error.
inline NodeClassifier::OnLeaf NodeClassifier::kind_on(uint64_t m, const LeafCode& leaf,
                                                      NodeKind* kind, uint8_t* covered) const {
  const int s = leaf.span_bits;
  if (s == 0) return OnLeaf::kCornerOrCentre;  // every node on a pixel is its corner
  const uint64_t diff = m ^ leaf.morton;
  const uint64_t offsets = diff & ((uint64_t{1} << s) - 1);
  const uint64_t midpoints = uint64_t{7} << (s - 3);
  if ((offsets & ~midpoints) != 0) return OnLeaf::kOffMidpoint;
  const unsigned inside = static_cast<unsigned>(offsets >> (s - 3));
  // How many of the three bits are set, from a table of 2-bit counts
  // (std::popcount is a dozen instructions on a baseline x86-64 build).
  const unsigned count = (0xE994u >> (2 * inside)) & 3;
  if (count == 0 || count == 3) return OnLeaf::kCornerOrCentre;
  *kind = count == 1 ? NodeKind::kEdge : NodeKind::kFace;
  *covered = kCoveredCells[inside | ((diff >> s) & 7) << 3];
  return OnLeaf::kDangles;
}

Status NodeClassifier::classify(uint64_t key, uint8_t mask, NodeKind* kind) {
  *kind = NodeKind::kAnchored;
  if (mask == 0xFF) return Status::Ok();
  // The one level a leaf it dangles from can have (cached_leaf): one above
  // the finest lattice the node lies on; below 0 for the root's corners.
  const int coarse = kMaxLevel - 1 - std::countr_zero(key | (uint64_t{1} << 63)) / 3;
  const int coarse_span = 3 * (kMaxLevel - coarse);
  uint8_t settled = mask;
  while (settled != 0xFF) {
    const int d = std::countr_zero(static_cast<unsigned>(static_cast<uint8_t>(~settled)));
    uint64_t p = 0;
    const LeafCode* leaf = nullptr;
    bool found = false;
    if (direction_pixel(key, d, &p)) {
      // The cache first, without a call or a Status: most pixels are in a
      // leaf found before.
      if (coarse >= 0 && (leaf = cached_leaf(p, coarse, coarse_span)) != nullptr) {
        found = true;
      } else {
        WEAVER_RETURN_IF_ERROR(search_leaf(p, &leaf, &found));
      }
    }
    if (!found) {  // outside the root or the domain
      settled |= static_cast<uint8_t>(1u << d);
      continue;
    }
    NodeKind here = NodeKind::kAnchored;
    uint8_t covered = 0;
    switch (kind_on(key, *leaf, &here, &covered)) {
      case OnLeaf::kDangles: break;
      case OnLeaf::kOffMidpoint: return unbalanced(key, leaf->key, mask);
      case OnLeaf::kCornerOrCentre: return overlapping(key, leaf->key);
    }
    if (*kind != NodeKind::kAnchored && here != *kind) return unbalanced(key, leaf->key, mask);
    *kind = here;
    settled |= covered | static_cast<uint8_t>(1u << d);  // (covered holds d: the leaf is there)
  }
  return Status::Ok();
}

// Every leaf that has m as a corner set its bit in the mask, so finding one
// with m as its corner (or centre) here means octants overlap.
Status NodeClassifier::overlapping(uint64_t m, uint64_t leaf_key) const {
  const Coord n = morton_decode(m);
  return Status::Corruption("node (" + std::to_string(n.x) + " " + std::to_string(n.y) + " " +
                            std::to_string(n.z) + ") is inconsistent with leaf " +
                            describe_octant(octant_from_key(leaf_key)) + ": overlapping octants?");
}

// Names the coarse leaf and a finer element that has node m as a corner.
Status NodeClassifier::unbalanced(uint64_t m, uint64_t coarse_key, uint8_t mask) {
  const std::string coarse_name = describe_octant(octant_from_key(coarse_key));
  std::string fine = "?";
  for (int d = 0; d < 8; ++d) {
    uint64_t p = 0;
    const LeafCode* leaf = nullptr;
    bool found = false;
    if (!((mask >> d) & 1) || !direction_pixel(m, d, &p)) continue;
    WEAVER_RETURN_IF_ERROR(search_leaf(p, &leaf, &found));
    if (found) {
      fine = describe_octant(octant_from_key(leaf->key));
      break;
    }
  }
  return Status::InvalidArgument("the octree is not 2:1 balanced: octant " + coarse_name +
                                 " and octant " + fine +
                                 " are face or edge neighbours more than one level apart");
}

}  // namespace weaver
