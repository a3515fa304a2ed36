// Explorer's neighbourhood questions: the elements across an element's
// faces, edges and corners, the elements around a node, and the dangling
// nodes that depend on a node.
#include <algorithm>

#include "query/explorer.h"

namespace weaver {
namespace {

// Whether child k of the region across direction d touches the element the
// region lies across: on each axis d crosses, the child must be on the side
// facing back (the low half across +, the high half across -).
bool child_faces_back(int k, Direction d) {
  const int8_t step[3] = {d.dx, d.dy, d.dz};
  for (int a = 0; a < 3; ++a) {
    const int bit = (k >> a) & 1;
    if ((step[a] > 0 && bit != 0) || (step[a] < 0 && bit != 1)) return false;
  }
  return true;
}

// Sorts items by id and drops repeats.
template <typename T>
void sort_unique_by_id(std::vector<T>* v) {
  std::sort(v->begin(), v->end(), [](const T& a, const T& b) { return a.id < b.id; });
  v->erase(std::unique(v->begin(), v->end(), [](const T& a, const T& b) { return a.id == b.id; }),
           v->end());
}

}  // namespace

std::string direction_name(Direction d) {
  std::string s;
  const int8_t step[3] = {d.dx, d.dy, d.dz};
  for (int a = 0; a < 3; ++a) {
    if (step[a] != 0) s += std::string(step[a] > 0 ? "+" : "-") + "xyz"[a];
  }
  return s;
}

Status Explorer::visit_across(const Octant& o, Direction d, const Octant& r,
                              std::vector<Neighbor>* out) {
  Neighbor n{d, 0, {}};
  bool found = false;
  WEAVER_RETURN_IF_ERROR(mesh_->leaf_covering(r, &found, &n.id, &n.octant));
  if (found) {
    out->push_back(n);
    return Status::Ok();
  }
  uint64_t inside = 0;
  WEAVER_RETURN_IF_ERROR(mesh_->leaves_inside(r, &inside));
  if (inside == 0 || r.level == kMaxLevel) return Status::Ok();  // a hole in the domain
  for (int k = 0; k < 8; ++k) {
    if (child_faces_back(k, d)) WEAVER_RETURN_IF_ERROR(visit_across(o, d, octant_child(r, k), out));
  }
  return Status::Ok();
}

Status Explorer::neighbors(uint64_t id, unsigned kinds, std::vector<Neighbor>* out) {
  out->clear();
  MeshElement e;
  WEAVER_RETURN_IF_ERROR(mesh_->element(id, false, &e));
  for (const Direction& d : kAllDirections) {
    Octant r;
    if (!(kinds >> d.nonzero() & 1) || !octant_neighbour(e.octant, d, &r)) continue;
    WEAVER_RETURN_IF_ERROR(visit_across(e.octant, d, r, out));
  }
  return Status::Ok();
}

Status Explorer::node_elements(uint64_t id, std::vector<NodeElement>* out) {
  MeshNode n;
  WEAVER_RETURN_IF_ERROR(node(id, &n));
  return elements_around(n, out);
}

Status Explorer::elements_around(const MeshNode& n, std::vector<NodeElement>* out) {
  out->clear();
  // The leaves whose closed boxes hold c are those holding one of the 8
  // pixels that have c as a corner.
  Coord pixels[8];
  size_t count = 0;
  const uint32_t c[3] = {n.c.x, n.c.y, n.c.z};
  for (int s = 0; s < 8; ++s) {
    uint32_t p[3];
    bool ok = true;
    for (int a = 0; a < 3; ++a) {
      const bool below = (s >> a) & 1;
      ok = ok && (below ? c[a] > 0 : c[a] < kRootEdge);
      p[a] = c[a] - (below ? 1 : 0);
    }
    if (ok) pixels[count++] = {p[0], p[1], p[2]};
  }
  PointHit hits[8];
  WEAVER_RETURN_IF_ERROR(locate_batch(pixels, count, hits));
  for (size_t i = 0; i < count; ++i) {
    if (!hits[i].inside) continue;
    NodeElement e{hits[i].id, hits[i].leaf, -1};
    for (int k = 0; k < 8; ++k) {
      if (octant_corner(e.octant, k) == n.c) e.corner = k;
    }
    out->push_back(e);
  }
  sort_unique_by_id(out);
  return Status::Ok();
}

Status Explorer::depends(uint64_t id, std::vector<MeshNode>* out) {
  out->clear();
  MeshNode a;
  WEAVER_RETURN_IF_ERROR(node(id, &a));
  std::vector<NodeElement> around;
  WEAVER_RETURN_IF_ERROR(elements_around(a, &around));
  // A node dangling on id sits at the midpoint of an edge, or the centre of
  // a face, that has id at a corner: an edge or face of an element around id.
  std::vector<Coord> candidates;
  for (const NodeElement& e : around) {
    const uint32_t h = octant_edge(e.octant) / 2;
    if (e.corner < 0 || h == 0) continue;
    int64_t step[3];
    for (int ax = 0; ax < 3; ++ax) step[ax] = ((e.corner >> ax) & 1) ? -int64_t{h} : int64_t{h};
    for (int mask = 1; mask < 8; ++mask) {
      if (mask == 7) continue;  // the element's centre is no node
      candidates.push_back({uint32_t(a.c.x + ((mask & 1) ? step[0] : 0)),
                            uint32_t(a.c.y + ((mask & 2) ? step[1] : 0)),
                            uint32_t(a.c.z + ((mask & 4) ? step[2] : 0))});
    }
  }
  std::vector<NodeHit> hits(candidates.size());
  WEAVER_RETURN_IF_ERROR(node_at_batch(candidates.data(), candidates.size(), hits.data()));
  // Elements around id share edges and faces: each dangling node once.
  hits.erase(
      std::remove_if(hits.begin(), hits.end(),
                     [](const NodeHit& h) { return !h.found || h.kind == NodeKind::kAnchored; }),
      hits.end());
  sort_unique_by_id(&hits);
  for (const NodeHit& h : hits) {
    MeshNode d;
    WEAVER_RETURN_IF_ERROR(node(h.id, &d));
    if (std::find(d.anchors.begin(), d.anchors.begin() + d.anchor_count, id) !=
        d.anchors.begin() + d.anchor_count) {
      out->push_back(d);
    }
  }
  return Status::Ok();
}

}  // namespace weaver
