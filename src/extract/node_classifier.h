// Deciding a node's kind, shared by both extraction algorithms.
//
// The input is the node's direction mask: bit d is set when the cell next to
// the node in direction d (bit a of d: the + side on axis a) holds an element
// that has the node as a corner.  A full mask means anchored.  Each empty
// cell is settled by an aggregate hit on its pixel: no leaf there means
// outside the domain; a leaf that does not have the node as a corner has it
// on an edge (one axis strictly inside the leaf) or a face (two axes), and
// the node dangles.  Direction counts and levels alone cannot tell a dangling
// node from one on a re-entrant corner of a non-cube domain; the hit can.  A
// node on a leaf's edge or face but off its midpoint or centre proves the
// octree is not 2:1 balanced.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "extract/extract.h"
#include "schema/node.h"
#include "schema/octant.h"
#include "schema/status.h"
#include "storage/btree.h"

namespace weaver {

// The direction bit an element contributes to its corner k: the element lies
// on the far side of that corner.
inline uint8_t corner_direction_bit(int k) { return static_cast<uint8_t>(1u << (~k & 7)); }

class NodeClassifier {
 public:
  // cache_bits: the cache of leaves holds 2^cache_bits keys
  // (cache_bits_for a budget).
  explicit NodeClassifier(BTree& octants, int cache_bits = kCacheBits)
      : octants_(octants),
        cache_(size_t{1} << cache_bits, kNoLeaf),
        cache_shift_(64 - cache_bits) {}

  // Leaves of the active bucket (sorted keys), searched instead of the
  // octant table for pixels whose Morton code is in [start, end): no other
  // leaf can hold those (bucket_worker.h).  They go into the cache of
  // leaves (cache_) when first searched.
  void set_local(const std::vector<uint64_t>* leaf_keys, uint64_t start, uint64_t end);
  // The cache of leaves holds 2^cache_bits keys for the classifier's life:
  // by default 4 slots for each of a bucket's 8192 leaves; extract sizes
  // it by its largest bucket (kSlotsPerLeaf slots a leaf), up to
  // 2^kMostCacheBits keys.
  static constexpr int kCacheBits = 15;
  static constexpr int kMostCacheBits = 16;
  static constexpr uint64_t kSlotsPerLeaf = 4;
  // The largest cache in `bytes` (at least 256 keys).
  static int cache_bits_for(uint64_t bytes) {
    int bits = 8;
    while (bits < kMostCacheBits && (sizeof(uint64_t) << (bits + 1)) <= bytes) ++bits;
    return bits;
  }

  Status classify(uint64_t key, uint8_t mask, NodeKind* kind);
  // Searches for a leaf made so far: the cache's misses.
  uint64_t searches() const { return searches_; }

  // A rank's part in extract_shard: pixels whose Morton code is below
  // `below` (the part's first node key) are looked up among the ghosts
  // (sorted leaf keys of earlier ranks, ghost_layer.h), not in the table.
  void set_ghosts(const std::vector<uint64_t>* ghosts, uint64_t below) {
    ghosts_ = ghosts;
    ghosts_below_ = below;
  }

 private:
  // A leaf as the classifier keeps it: its Morton code and the bits below
  // its level (it holds the pixels and nodes that share its code above
  // them), never decoded on the way (a node's kind is read from the codes).
  struct LeafCode {
    uint64_t morton = UINT64_MAX;  // an empty entry's is past every pixel's
    int span_bits = 0;
    uint64_t key = 0;  // its octant key, for messages
  };

  // The leaf holding pixel pm (its Morton code), searched for, and put in
  // the cache; *leaf is valid until the next call.
  Status search_leaf(uint64_t pm, const LeafCode** leaf, bool* found);
  // The octant table's last key <= pk, through table_blocks_.
  Status table_floor(uint64_t pk, uint64_t* key, bool* hit);
  // Node m (its Morton code) on the closure of `leaf`: dangling from it, or
  // off the midpoint of its edge or face (unbalanced), or at its corner or
  // centre (overlapping octants).
  enum class OnLeaf { kDangles, kOffMidpoint, kCornerOrCentre };
  OnLeaf kind_on(uint64_t m, const LeafCode& leaf, NodeKind* kind, uint8_t* covered) const;
  Status overlapping(uint64_t m, uint64_t leaf_key) const;
  Status unbalanced(uint64_t m, uint64_t coarse_key, uint8_t mask);

  BTree& octants_;
  const std::vector<uint64_t>* ghosts_ = nullptr;
  uint64_t ghosts_below_ = 0;
  const std::vector<uint64_t>* leaf_keys_ = nullptr;
  uint64_t local_start_ = 0, local_end_ = 0;
  bool local_cached_ = false;  // the active bucket's leaves are in cache_
  // Blocks of the octant table's keys read last (BTree::floor_block), each
  // answering the floors of the keys in [lo, limit): the pixels before a
  // bucket are asked for again and again near one another, and a descent
  // and block decode for each was a twelfth of a random octree's extract.
  struct TableBlock {
    uint64_t lo = UINT64_MAX, limit = 0;  // empty
    uint32_t count = 0;
    uint64_t keys[64];
  };
  // 16: random 1M's extract decodes 12.3K blocks against 17.3K with 4
  // (1.577G instructions against 1.590G); 32 and 64 cost more to search
  // than they save.
  static constexpr int kTableBlocks = 16;
  TableBlock table_blocks_[kTableBlocks];
  int next_table_block_ = 0;  // the one replaced next
  // Leaves by their key's hash, one a slot, each slot holding the last
  // leaf hashed to it (the octree does not change, so they stay valid
  // across buckets).  A node dangling in a 2:1 balanced octree hangs on
  // leaves one level coarser than the finest lattice it lies on (it is an
  // odd multiple of their half edge on the axes it is inside them), so the
  // leaf holding an empty cell around it has one candidate key, looked up
  // here before any search.  A coarse leaf is asked for by up to 18 nodes
  // (its face centres and edge midpoints) scattered in Z-order: the 8 leaves
  // found last in each direction, kept before, answered 46% of random 1M's
  // questions, this cache with the bucket's leaves put in when it is first
  // searched 94% (callgrind: 1.58G -> 1.36G instructions).
  static constexpr uint64_t kNoLeaf = ~uint64_t{0};  // no octant key has every bit set
  std::vector<uint64_t> cache_;
  int cache_shift_;  // 64 less the cache's bits
  LeafCode handed_;  // the leaf cached_leaf or search_leaf handed out last
  uint64_t searches_ = 0;
  size_t cache_slot(uint64_t key) const {
    return static_cast<size_t>((key * 0x9E3779B97F4A7C15ULL) >> cache_shift_);
  }
  // The cached leaf at `level` (its codes' span_bits, 3 * (kMaxLevel -
  // level), given) holding pixel pm, or null.
  const LeafCode* cached_leaf(uint64_t pm, int level, int span_bits) {
    const uint64_t morton = pm >> span_bits << span_bits;
    const uint64_t key = (morton >> 3) << 7 | static_cast<uint64_t>(level);  // (level < 20)
    if (cache_[cache_slot(key)] != key) return nullptr;
    handed_ = {morton, span_bits, key};
    return &handed_;
  }
  void remember(uint64_t key) { cache_[cache_slot(key)] = key; }
};

inline void count_kind(NodeKind k, ExtractResult* r) {
  ++r->nodes;
  if (k == NodeKind::kAnchored) ++r->anchored;
  if (k == NodeKind::kEdge) ++r->edge;
  if (k == NodeKind::kFace) ++r->face;
}

}  // namespace weaver
