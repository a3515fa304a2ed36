#include "verify/mesh_check.h"

#include <algorithm>
#include <array>
#include <string>

#include "db/leaf_window.h"
#include "schema/node.h"
#include "schema/octant.h"

namespace weaver {
namespace {

std::string describe_point(Coord p) {
  return "(" + std::to_string(p.x) + " " + std::to_string(p.y) + " " + std::to_string(p.z) + ")";
}

// The leaf holding a pixel: one aggregate hit, after a look at the few
// leaves found last (neighbouring nodes share most of their leaves), each
// kept with its key range so that the look compares pixel keys.
class LeafFinder {
 public:
  explicit LeafFinder(BTree& octants) : octants_(octants, false) {}

  // *leaf: the leaf, valid until the next call; null if no leaf holds it.
  Status find(Coord pixel, const Octant** leaf) {
    const uint64_t pk = pixel_key(pixel);
    for (const Recent& r : recent_) {
      if (r.key <= pk && pk < r.end) return *leaf = &r.leaf, Status::Ok();
    }
    *leaf = nullptr;
    LeafWindow::Floor f;
    WEAVER_RETURN_IF_ERROR(octants_.floor(pk, &f));
    const uint64_t key = f.key;
    if (!f.found || pk >= octant_key_subtree_end(key)) return Status::Ok();
    Recent& r = recent_[next_++ % recent_.size()];
    r.key = key;
    r.end = octant_key_subtree_end(key);
    octant_decode_into(key, &r.leaf);
    *leaf = &r.leaf;
    return Status::Ok();
  }

 private:
  struct Recent {
    uint64_t key = 1, end = 0;  // [key, end): the keys of the leaf's pixels; empty at first
    Octant leaf{};
  };
  LeafWindow octants_;
  std::array<Recent, 16> recent_{};
  size_t next_ = 0;
};

// Where node p sits on a leaf whose closure holds it.
enum class Place { kCorner, kEdgeMidpoint, kFaceCentre, kElsewhere };

Place place_on(Coord p, const Octant& leaf) {
  const uint32_t e = octant_edge(leaf);
  const uint32_t rel[3] = {p.x - leaf.x, p.y - leaf.y, p.z - leaf.z};
  int inside = 0, mid = 0;
  for (uint32_t r : rel) {
    if (r != 0 && r != e) ++inside;
    if (r == e / 2) ++mid;
  }
  if (inside == 0) return Place::kCorner;
  if (inside == mid && inside == 1) return Place::kEdgeMidpoint;
  if (inside == mid && inside == 2) return Place::kFaceCentre;
  return Place::kElsewhere;
}

class NodeChecker {
 public:
  NodeChecker(BTree& octants, BTree& nodes, Problems& problems, VerifyReport* report)
      : finder_(octants), nodes_(nodes, true), problems_(problems), report_(report) {}

  // Checks the node with this key, stored kind and id.
  Status check(uint64_t key, uint8_t stored, uint64_t id) {
    const Coord p = morton_decode(key);
    // Made only for a problem: a string per node would cost more than the check.
    const auto name = [&] { return "node " + std::to_string(id) + " at " + describe_point(p); };
    if (!node_is_valid(p)) return problem(name() + ": outside the address space");
    if (stored > 2) return problem(name() + ": unknown kind " + std::to_string(stored));
    int corners = 0;
    bool edge = false, face = false;
    for (int d = 0; d < 8; ++d) {
      // The cell of one tick on side d of p.
      const uint32_t dx = d & 1, dy = (d >> 1) & 1, dz = (d >> 2) & 1;
      if ((dx && p.x == 0) || (dy && p.y == 0) || (dz && p.z == 0)) continue;
      const Coord cell{p.x - dx, p.y - dy, p.z - dz};
      if (!pixel_is_valid(cell)) continue;
      const Octant* leaf = nullptr;
      WEAVER_RETURN_IF_ERROR(finder_.find(cell, &leaf));
      if (leaf == nullptr) continue;
      switch (place_on(p, *leaf)) {
        case Place::kCorner: ++corners; break;
        case Place::kEdgeMidpoint: edge = true; break;
        case Place::kFaceCentre: face = true; break;
        case Place::kElsewhere:
          return problem(name() + " lies on element " + describe_octant(*leaf) +
                         " away from its corners and midpoints (unbalanced mesh?)");
      }
    }
    report_->corners += corners;
    if (corners == 0) return problem(name() + " is not a corner of any element");
    const NodeKind expected = edge ? NodeKind::kEdge : face ? NodeKind::kFace : NodeKind::kAnchored;
    const auto kind = static_cast<NodeKind>(stored);
    if (kind != expected) {
      return problem(name() + " is stored as " + node_kind_name(kind) +
                     ", the leaves around it make it " + node_kind_name(expected));
    }
    if (kind != NodeKind::kAnchored) ++report_->dangling;
    return check_anchors(p, kind, name);
  }

 private:
  template <class Name>
  Status check_anchors(Coord p, NodeKind kind, const Name& name) {
    Coord anchors[4];
    const int n = node_anchors(p, kind, anchors);
    for (int i = 0; i < n; ++i) {
      const std::byte* k = nullptr;
      bool found = false;
      WEAVER_RETURN_IF_ERROR(nodes_.get(node_key(anchors[i]), &k, &found));
      if (!found)
        return problem(name() + ": its anchor " + describe_point(anchors[i]) + " is not a node");
      // Face+edge 2:1 balance keeps every anchor anchored where the leaves
      // fill their parents; next to holes finer than that it cannot (a
      // fine leaf may touch a leaf two levels coarser at a point alone).
      if (static_cast<NodeKind>(*k) != NodeKind::kAnchored) {
        return problem(name() + ": its anchor " + describe_point(anchors[i]) +
                       " is not anchored (it dangles too: a chain of dependencies, which "
                       "holes in the domain finer than the leaves' parents allow)");
      }
    }
    return Status::Ok();
  }

  Status problem(std::string text) {
    problems_.add(std::move(text));
    return Status::Ok();
  }

  LeafFinder finder_;
  LeafWindow nodes_;
  Problems& problems_;
  VerifyReport* report_;
};

// Called when the corner count is short: names the first element with a
// corner that is not a node.
Status find_missing_corner(BTree& octants, BTree& nodes, Problems& problems) {
  BTreeCursor c;
  WEAVER_RETURN_IF_ERROR(octants.seek_cursor(0, &c));
  for (uint64_t id = 0; c.valid(); ++id) {
    const Octant o = octant_from_key(c.key());
    for (int k = 0; k < 8; ++k) {
      bool found = false;
      WEAVER_RETURN_IF_ERROR(nodes.get(node_key(octant_corner(o, k)), nullptr, &found));
      if (!found) {
        problems.add("element " + std::to_string(id) + " " + describe_octant(o) + ": corner " +
                     describe_point(octant_corner(o, k)) + " is not a node");
        return Status::Ok();
      }
    }
    WEAVER_RETURN_IF_ERROR(c.next());
  }
  return Status::Ok();
}

}  // namespace

Status check_node_range(BTree& octants, BTree& nodes, uint64_t first, uint64_t end,
                        const std::function<void(uint64_t)>& checked, Problems& problems,
                        VerifyReport* report) {
  NodeChecker checker(octants, nodes, problems, report);
  if (first >= end) return Status::Ok();
  uint64_t first_key = 0;
  WEAVER_RETURN_IF_ERROR(nodes.select(first, &first_key, nullptr));
  BTreeCursor c;
  WEAVER_RETURN_IF_ERROR(nodes.seek_cursor(first_key, &c));
  uint64_t id = first;
  for (; id < end && c.valid() && !problems.full(); ++id) {
    if ((id - first) % (1 << 16) == 0 && id > first) checked(1 << 16);
    WEAVER_RETURN_IF_ERROR(checker.check(c.key(), static_cast<uint8_t>(c.payload()[0]), id));
    WEAVER_RETURN_IF_ERROR(c.next());
  }
  report->nodes = id - first;
  return Status::Ok();
}

Status check_corner_total(BTree& octants, BTree& nodes, Problems& problems, VerifyReport* report) {
  report->elements = octants.size();
  if (problems.full() || report->nodes != nodes.size()) return Status::Ok();
  if (report->corners != 8 * octants.size()) {
    const size_t before = report->problems.size();
    WEAVER_RETURN_IF_ERROR(find_missing_corner(octants, nodes, problems));
    if (report->problems.size() == before) {
      problems.add("element corners found at nodes: " + std::to_string(report->corners) +
                   ", expected 8 x " + std::to_string(octants.size()));
    }
  }
  return Status::Ok();
}

}  // namespace weaver
