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

// Appends to *out the leaves of `octants` across each face of leaf o, face
// by face, each face's in key order: one leaf of o's size or larger, or all
// the finer leaves that touch the face.  Nothing across the domain's
// boundary.  Works on any octree, balanced or not.
Status face_neighbors(BTree& octants, const Octant& o, std::vector<FaceNeighbor>* out);

}  // namespace weaver
