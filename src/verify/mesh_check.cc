#include "verify/mesh_check.h"

#include <algorithm>
#include <array>
#include <string>

#include "db/leaf_window.h"
#include "schema/node.h"
#include "schema/octant.h"

namespace weaver {
// Not anonymous: NodeStreamCheck::State holds a NodeChecker.
namespace node_check {

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

  // The leaves in the 8 cells of one tick around p (a leaf in several of
  // them once for each), *n of them.
  Status leaves_around(Coord p, std::array<Octant, 8>* leaves, int* n) {
    *n = 0;
    for (int d = 0; d < 8; ++d) {
      const uint32_t dx = d & 1, dy = (d >> 1) & 1, dz = (d >> 2) & 1;
      if ((dx && p.x == 0) || (dy && p.y == 0) || (dz && p.z == 0)) continue;
      const Coord cell{p.x - dx, p.y - dy, p.z - dz};
      if (!pixel_is_valid(cell)) continue;
      const Octant* leaf = nullptr;
      WEAVER_RETURN_IF_ERROR(finder_.find(cell, &leaf));
      if (leaf != nullptr) (*leaves)[(*n)++] = *leaf;
    }
    return Status::Ok();
  }

  // How many leaves have p as a corner.
  Status corners_at(Coord p, int* corners) {
    std::array<Octant, 8> leaves;
    int n = 0;
    WEAVER_RETURN_IF_ERROR(leaves_around(p, &leaves, &n));
    *corners = 0;
    for (int i = 0; i < n; ++i) *corners += place_on(p, leaves[i]) == Place::kCorner;
    return Status::Ok();
  }

  // The anchors of dangling node id (key, kind): nodes, and anchored.
  Status anchors(uint64_t key, NodeKind kind, uint64_t id) {
    return check_anchors(key, kind, [&] {
      return "node " + std::to_string(id) + " at " + describe_point(morton_decode(key));
    });
  }

  // Checks the node with this key, stored kind and id.
  Status check(uint64_t key, uint8_t stored, uint64_t id) {
    const Coord p = morton_decode(key);
    // Made only for a problem: a string per node would cost more than the check.
    const auto name = [&] { return "node " + std::to_string(id) + " at " + describe_point(p); };
    if (!node_is_valid(p)) return problem(name() + ": outside the address space");
    if (stored > 2) return problem(name() + ": unknown kind " + std::to_string(stored));
    int corners = 0;
    bool edge = false, face = false;
    std::array<Octant, 8> leaves;
    int n = 0;
    WEAVER_RETURN_IF_ERROR(leaves_around(p, &leaves, &n));
    for (int i = 0; i < n; ++i) {
      switch (place_on(p, leaves[i])) {
        case Place::kCorner: ++corners; break;
        case Place::kEdgeMidpoint: edge = true; break;
        case Place::kFaceCentre: face = true; break;
        case Place::kElsewhere:
          return problem(name() + " lies on element " + describe_octant(leaves[i]) +
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
    return check_anchors(key, kind, name);
  }

 private:
  // The node's anchors from its key (node_anchor_keys: no decoding, the
  // coordinates made only for a message).
  template <class Name>
  Status check_anchors(uint64_t node, NodeKind kind, const Name& name) {
    uint64_t anchors[4];
    const int n = node_anchor_keys(node, kind, anchors);
    for (int i = 0; i < n; ++i) {
      const uint64_t key = anchors[i];
      // Neighbouring dangling nodes share anchors: those found anchored
      // lately need no second lookup.
      uint64_t& seen = anchored_[(key * 0x9E3779B97F4A7C15ull) >> (64 - kAnchoredBits)];
      if (seen == key + 1) continue;
      const std::byte* k = nullptr;
      bool found = false;
      WEAVER_RETURN_IF_ERROR(nodes_.get(key, &k, &found));
      if (!found)
        return problem(name() + ": its anchor " + describe_point(morton_decode(key)) +
                       " is not a node");
      // Face+edge 2:1 balance keeps every anchor anchored where the leaves
      // fill their parents; next to holes finer than that it cannot (a
      // fine leaf may touch a leaf two levels coarser at a point alone).
      if (static_cast<NodeKind>(*k) != NodeKind::kAnchored) {
        return problem(name() + ": its anchor " + describe_point(morton_decode(key)) +
                       " is not anchored (it dangles too: a chain of dependencies, which "
                       "holes in the domain finer than the leaves' parents allow)");
      }
      seen = key + 1;
    }
    return Status::Ok();
  }

  static constexpr int kAnchoredBits = 12;
  std::vector<uint64_t> anchored_ = std::vector<uint64_t>(size_t{1} << kAnchoredBits);  // key + 1

  Status problem(std::string text) {
    problems_.add(std::move(text));
    return Status::Ok();
  }

  LeafFinder finder_;
  LeafWindow nodes_;
  Problems& problems_;
  VerifyReport* report_;
};

}  // namespace node_check

namespace {

using node_check::describe_point;

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

// The stored table walked beside the derived records.
using node_check::NodeChecker;

struct NodeStreamCheck::State {
  State(BTree& octants, BTree& nodes, Problems& problems, VerifyReport* report)
      : checker(octants, nodes, problems, report) {}
  NodeChecker checker;
  BTreeCursor stored;
  uint64_t id = 0;  // the stored node at the cursor
};

NodeStreamCheck::NodeStreamCheck(BTree& octants, BTree& nodes, Problems& problems,
                                 VerifyReport* report)
    : nodes_(nodes),
      problems_(problems),
      report_(report),
      state_(std::make_unique<State>(octants, nodes, problems, report)) {}

NodeStreamCheck::~NodeStreamCheck() = default;

Status NodeStreamCheck::open() { return nodes_.seek_cursor(0, &state_->stored); }

// A stored node the derivation does not give as stored: checked alone, as
// the per-node check did, for the message that says why.
Status NodeStreamCheck::stored_differs() {
  State& s = *state_;
  const size_t before = report_->problems.size();
  const uint64_t corners = report_->corners;
  WEAVER_RETURN_IF_ERROR(
      s.checker.check(s.stored.key(), static_cast<uint8_t>(s.stored.payload()[0]), s.id));
  report_->corners = corners;  // counted from the derivation
  if (report_->problems.size() == before) {
    problems_.add("node " + std::to_string(s.id) + " at " +
                  describe_point(morton_decode(s.stored.key())) +
                  " differs from the node the leaves around it make");
  }
  return Status::Ok();
}

Status NodeStreamCheck::compare(const uint64_t* keys, const std::byte* kinds, size_t n) {
  State& s = *state_;
  for (size_t i = 0; i < n && !problems_.full(); ++i) {
    const uint64_t key = keys[i];
    const auto kind = static_cast<NodeKind>(kinds[i]);
    while (s.stored.valid() && s.stored.key() < key && !problems_.full()) {
      WEAVER_RETURN_IF_ERROR(stored_differs());  // no element has it as a corner
      WEAVER_RETURN_IF_ERROR(next_stored());
    }
    if (!s.stored.valid() || s.stored.key() != key) {
      const Coord p = morton_decode(key);
      int corners = 0;
      WEAVER_RETURN_IF_ERROR(s.checker.corners_at(p, &corners));
      missing_corners_ += uint64_t(corners);
      problems_.add("element corner " + describe_point(p) + " (of " + std::to_string(corners) +
                    " elements) is not a node");
      continue;
    }
    if (static_cast<NodeKind>(s.stored.payload()[0]) != kind) {
      WEAVER_RETURN_IF_ERROR(stored_differs());
    } else if (kind != NodeKind::kAnchored) {
      ++report_->dangling;
      WEAVER_RETURN_IF_ERROR(s.checker.anchors(key, kind, s.id));
    }
    WEAVER_RETURN_IF_ERROR(next_stored());
  }
  return Status::Ok();
}

Status NodeStreamCheck::next_stored() {
  ++state_->id;
  ++report_->nodes;
  return state_->stored.next();
}

Status NodeStreamCheck::finish(uint64_t elements) {
  State& s = *state_;
  while (s.stored.valid() && !problems_.full()) {
    WEAVER_RETURN_IF_ERROR(stored_differs());
    WEAVER_RETURN_IF_ERROR(next_stored());
  }
  // Every element has 8 corners among the derived nodes: those found at
  // stored nodes are all but the missing nodes' ones.
  report_->elements = elements;
  report_->corners = 8 * elements - missing_corners_;
  return Status::Ok();
}

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
