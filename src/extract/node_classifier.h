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
  explicit NodeClassifier(BTree& octants) : octants_(octants) {}

  // Leaves of the active bucket (sorted keys), searched instead of the
  // octant table for pixels whose Morton code is in [start, end): no other
  // leaf can hold those (bucket_worker.h).  They are indexed (slot_first_)
  // when first searched.
  void set_local(const std::vector<uint64_t>* leaf_keys, uint64_t start, uint64_t end);
  // Bytes of the index per local leaf, at most.
  static constexpr uint64_t kIndexBytesPerLeaf = 4;

  Status classify(uint64_t key, uint8_t mask, NodeKind* kind);

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

  // pm is the Morton code of the pixel in `direction` (0..7) of a node.
  // *leaf points into recent_: valid until the next call.
  Status leaf_at(uint64_t pm, int direction, const LeafCode** leaf, bool* found);
  Status search_leaf(uint64_t pm, int direction, const LeafCode** leaf, bool* found);
  // The last local leaf key <= pk, pm's pixel key, or null.
  const uint64_t* local_floor(uint64_t pm, uint64_t pk) const;
  void index_local();
  // The octant table's last key <= pk, through table_blocks_.
  Status table_floor(uint64_t pk, uint64_t* key, bool* hit);
  // One of recent_ that holds pixel pm, or null.
  const LeafCode* recent_leaf(uint64_t pm) const;
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
  // The local range cut into equal slots of 2^slot_shift_ Morton codes, one for
  // every one or two leaves: slot_first_[s] is the first leaf whose anchor is in
  // slot s or later.  A pixel's floor is then found among the few leaves of
  // its slot, not by a binary search over the whole bucket (a cache miss a
  // step on a graded mesh's large buckets).
  std::vector<uint32_t> slot_first_;
  int slot_shift_ = 0;
  bool indexed_ = false;  // slot_first_ is the active bucket's
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
  // The leaf leaf_at found last in each direction (the octree does not
  // change, so they stay valid across buckets).
  LeafCode recent_[8];
};

inline void count_kind(NodeKind k, ExtractResult* r) {
  ++r->nodes;
  if (k == NodeKind::kAnchored) ++r->anchored;
  if (k == NodeKind::kEdge) ++r->edge;
  if (k == NodeKind::kFace) ++r->face;
}

}  // namespace weaver
