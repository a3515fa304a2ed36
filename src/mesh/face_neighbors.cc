#include "mesh/face_neighbors.h"

namespace weaver {
namespace {

struct FaceWalk {
  BTree& t;
  int face;
  std::vector<FaceNeighbor>* out;

  // Collects the leaves that hold r or lie in r and touch the face; r is an
  // aligned octant across the face.
  Status visit(const Octant& r) {
    const uint64_t key = octant_key(r);
    uint64_t floor_key = 0;
    bool found = false;
    WEAVER_RETURN_IF_ERROR(t.floor(key, &floor_key, nullptr, &found));
    if (found) {
      const Octant leaf = octant_from_key(floor_key);
      if (leaf == r || octant_is_ancestor(leaf, r)) {
        FaceNeighbor n{face, 0, leaf};
        bool present = false;
        WEAVER_RETURN_IF_ERROR(t.rank_exact(floor_key, &n.id, &present));
        out->push_back(n);
        return Status::Ok();
      }
    }
    if (r.level >= kMaxLevel) return Status::Ok();
    uint64_t first = 0, end = 0;
    WEAVER_RETURN_IF_ERROR(t.rank(key, &first));
    WEAVER_RETURN_IF_ERROR(t.rank(octant_key_subtree_end(r), &end));
    if (first == end) return Status::Ok();  // outside the domain
    // The children of r on the face's side: bit `axis` of the child index
    // is 0 when r lies above the face, 1 when below.
    const int axis = face / 2, bit = (face % 2 == 1) ? 0 : 1;
    for (int k = 0; k < 8; ++k) {
      if (((k >> axis) & 1) == bit) WEAVER_RETURN_IF_ERROR(visit(octant_child(r, k)));
    }
    return Status::Ok();
  }
};

}  // namespace

Status face_neighbors(BTree& octants, const Octant& o, std::vector<FaceNeighbor>* out) {
  const uint32_t s = octant_edge(o);
  for (int face = 0; face < kFaces; ++face) {
    const int axis = face / 2;
    uint32_t c[3] = {o.x, o.y, o.z};
    if (face % 2 == 0) {
      if (c[axis] == 0) continue;  // the root's boundary
      c[axis] -= s;
    } else {
      if (c[axis] + s >= kRootEdge) continue;
      c[axis] += s;
    }
    FaceWalk walk{octants, face, out};
    WEAVER_RETURN_IF_ERROR(walk.visit(Octant{c[0], c[1], c[2], o.level}));
  }
  return Status::Ok();
}

}  // namespace weaver
