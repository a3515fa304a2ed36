// Face adjacency of the elements of an octree mesh: the elements that share
// a face (a piece of positive area) with a given one.  Across a 2:1 step a
// coarse face is shared with up to 4 finer elements; this is the dual graph
// that a partitioner needs (METIS's mpmetis builds its graph from shared
// nodes and misses exactly those faces on a non-conforming mesh).
#pragma once

#include <cstdint>
#include <vector>

#include "schema/octant.h"
#include "schema/status.h"
#include "storage/btree.h"

namespace weaver {

// Faces of an element: 2 * axis + side, side 0 the low face (-x, -y, -z),
// side 1 the high one.
inline constexpr int kFaces = 6;

struct FaceNeighbor {
  int face = 0;  // the face of the element it lies across
  uint64_t id = 0;
  Octant octant;
};

// Finds face neighbours by floor and rank queries on the octant table,
// answered where it can from a decoded leaf kept for each face direction:
// for leaves visited in Z-order, the leaves across the same face of
// consecutive ones mostly lie in the same table leaf.
class FaceFinder {
 public:
  explicit FaceFinder(BTree& octants) : t_(octants) {}

  // Appends to *out the leaves across each face of leaf o, face by face,
  // each face's in key order: one leaf of o's size or larger, or all the
  // finer leaves that touch the face.  Nothing across the domain's boundary.
  // Works on any octree, balanced or not.  Only the faces with their bit
  // set in `faces` (bit f for face f) are looked at.
  Status find(const Octant& o, std::vector<FaceNeighbor>* out, unsigned faces = 0x3F);

 private:
  struct Leaf {
    std::vector<uint64_t> keys;  // a table leaf's keys, decoded
    uint64_t first_rank = 0;
  };
  // A few leaves for one face direction: across a face in -z or +z, say,
  // consecutive elements alternate between leaves far apart in Z-order.
  struct Ways {
    static constexpr int kWays = 4;
    Leaf leaf[kWays];
    int next = 0;  // replaced on the next miss
  };
  Status visit(int face, const Octant& r, std::vector<FaceNeighbor>* out);
  // The largest key <= key and its rank; *found false if there is none.
  Status floor_rank(Ways& w, uint64_t key, uint64_t* floor_key, uint64_t* rank, bool* found);
  // The number of keys < key.
  Status rank(Ways& w, uint64_t key, uint64_t* out);
  // The cached leaf whose keys span key, or a new one where key is or would be.
  Status leaf_for(Ways& w, uint64_t key, Leaf** out);

  BTree& t_;
  Ways ways_[kFaces];
};

}  // namespace weaver
