#include "mesh/face_neighbors.h"

#include <algorithm>

namespace weaver {

Status FaceFinder::leaf_for(Ways& w, uint64_t key, Leaf** out) {
  for (Leaf& l : w.leaf) {
    if (!l.keys.empty() && l.keys.front() <= key && key <= l.keys.back()) {
      *out = &l;
      return Status::Ok();
    }
  }
  Leaf& l = w.leaf[w.next];
  w.next = (w.next + 1) % Ways::kWays;
  *out = &l;
  return t_.leaf_keys(key, &l.keys, &l.first_rank);
}

Status FaceFinder::rank(Ways& w, uint64_t key, uint64_t* out) {
  // In the leaf where key is or would be, its rank is the leaf's first rank
  // plus its position; a key within a cached leaf's span needs no descent.
  Leaf* l = nullptr;
  WEAVER_RETURN_IF_ERROR(leaf_for(w, key, &l));
  *out = l->first_rank +
         uint64_t(std::lower_bound(l->keys.begin(), l->keys.end(), key) - l->keys.begin());
  return Status::Ok();
}

Status FaceFinder::floor_rank(Ways& w, uint64_t key, uint64_t* floor_key, uint64_t* rank,
                              bool* found) {
  Leaf* lp = nullptr;
  WEAVER_RETURN_IF_ERROR(leaf_for(w, key, &lp));
  const Leaf& l = *lp;
  if (l.keys.empty() || key < l.keys.front()) {
    // The floor lies in an earlier leaf (or there is none): ask the tree.
    WEAVER_RETURN_IF_ERROR(t_.floor(key, floor_key, nullptr, found));
    if (!*found) return Status::Ok();
    bool present = false;
    return t_.rank_exact(*floor_key, rank, &present);
  }
  const size_t i = size_t(std::upper_bound(l.keys.begin(), l.keys.end(), key) - l.keys.begin()) - 1;
  *floor_key = l.keys[i];
  *rank = l.first_rank + i;
  *found = true;
  return Status::Ok();
}

// Collects the leaves that hold r or lie in r and touch the face; r is an
// aligned octant across the face.
Status FaceFinder::visit(int face, const Octant& r, std::vector<FaceNeighbor>* out) {
  Ways& l = ways_[face];
  const uint64_t key = octant_key(r);
  uint64_t floor_key = 0, id = 0;
  bool found = false;
  WEAVER_RETURN_IF_ERROR(floor_rank(l, key, &floor_key, &id, &found));
  if (found) {
    const Octant leaf = octant_from_key(floor_key);
    if (leaf == r || octant_is_ancestor(leaf, r)) {
      out->push_back({face, id, leaf});
      return Status::Ok();
    }
  }
  if (r.level >= kMaxLevel) return Status::Ok();
  uint64_t first = 0, end = 0;
  WEAVER_RETURN_IF_ERROR(rank(l, key, &first));
  WEAVER_RETURN_IF_ERROR(rank(l, octant_key_subtree_end(r), &end));
  if (first == end) return Status::Ok();  // outside the domain
  // The children of r on the face's side: bit `axis` of the child index
  // is 0 when r lies above the face, 1 when below.
  const int axis = face / 2, bit = (face % 2 == 1) ? 0 : 1;
  for (int k = 0; k < 8; ++k) {
    if (((k >> axis) & 1) == bit) WEAVER_RETURN_IF_ERROR(visit(face, octant_child(r, k), out));
  }
  return Status::Ok();
}

Status FaceFinder::find(const Octant& o, std::vector<FaceNeighbor>* out, unsigned faces) {
  const uint32_t s = octant_edge(o);
  for (int face = 0; face < kFaces; ++face) {
    if ((faces >> face & 1) == 0) continue;
    const int axis = face / 2;
    uint32_t c[3] = {o.x, o.y, o.z};
    if (face % 2 == 0) {
      if (c[axis] == 0) continue;  // the root's boundary
      c[axis] -= s;
    } else {
      if (c[axis] + s >= kRootEdge) continue;
      c[axis] += s;
    }
    WEAVER_RETURN_IF_ERROR(visit(face, Octant{c[0], c[1], c[2], o.level}, out));
  }
  return Status::Ok();
}

}  // namespace weaver
