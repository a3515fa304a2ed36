// An open mesh database that answers questions: what is at a point (one, or
// a batch of millions), an element or node by id, and the neighbourhood of
// either.  Opened once (a read snapshot of the last commit) and asked many
// times: by `weaver query`, by `weaver shell`, and by the library API.
// The octree alone answers the point questions; ids of nodes need the
// extracted mesh.
#pragma once

#include <algorithm>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "db/leaf_window.h"
#include "mesh/mesh_reader.h"
#include "model/ground_model.h"
#include "query/aggregates.h"
#include "schema/octant.h"
#include "schema/status.h"
#include "util/memory_budget.h"

namespace weaver {

// Where an Explorer's memory goes: the shares of --memory.
struct ExplorerMemory {
  explicit ExplorerMemory(MemoryBudget budget) : plan(budget) {
    // The pools keep the paths and leaves of recent questions, and the
    // directories take a question straight to its leaf (at 2 Hz, 1.3B
    // leaves, the octant table's is 7 MB); a batch of points, sorted, and
    // its answers take the rest.
    octant_pool = plan.take("octant table pool", 2, 8);
    octant_directory = plan.take("octant table directory", 1, 8);
    node_pool = plan.take("node table pool", 2, 8);
    node_directory = plan.take("node table directory", 1, 8);
    batch = plan.take("point batch", 1, 4);
  }
  MemoryPlan plan;
  uint64_t octant_pool = 0, octant_directory = 0, node_pool = 0, node_directory = 0, batch = 0;
};

// A point of a batch as the tables are walked: its key and its index in the
// batch.
using KeyedPoint = std::pair<uint64_t, uint64_t>;

// The leaf that holds a point, with its material (zeros without one).
struct PointHit {
  bool inside = false;  // false: outside the domain (no leaf holds the point)
  uint64_t id = 0;      // element id: the leaf's rank in key order
  Octant leaf;
  float vp = 0, vs = 0, rho = 0;
  float qp = 0, qs = 0;  // when the mesh has them (Mesh::has_q)
};

// The node at a point.
struct NodeHit {
  bool found = false;
  uint64_t id = 0;
  NodeKind kind = NodeKind::kAnchored;
};

// An element across a face, edge or corner of another.
struct Neighbor {
  Direction dir;  // from the element asked about
  uint64_t id = 0;
  Octant octant;
};

// An element whose closed box holds a node.
struct NodeElement {
  uint64_t id = 0;
  Octant octant;
  int corner = -1;  // which corner of it the node is; -1: it hangs on its edge or face
};

class Explorer {
 public:
  // Opens db_dir read-only within `memory` (the table caches).  The node
  // table is optional: without it, only the octree's questions are answered.
  static Status open(const std::string& db_dir, MemoryBudget memory,
                     std::unique_ptr<Explorer>* out);

  Mesh& mesh() { return *mesh_; }
  bool has_nodes() const { return mesh_->has_nodes(); }
  const Units& units() const { return mesh_->units(); }
  uint64_t element_count() const { return mesh_->element_count(); }
  uint64_t node_count() const { return mesh_->node_count(); }
  // NotFound "no mesh yet" unless the node table exists: what every node
  // question below returns without one.
  Status require_nodes() const;
  // How many points a batch should hold to stay within the memory budget:
  // a point costs its coordinate (12 bytes), its sort pair (16) and its
  // answer: about 80 bytes with the caller's own buffers.
  size_t batch_points() const {
    return size_t(std::clamp<uint64_t>(batch_bytes_ / 80, 4096, 1 << 22));
  }
  // The budget's share for a batch, for a caller that holds the batch's
  // buffers itself (cli/point_batch.h).
  uint64_t batch_bytes() const { return batch_bytes_; }

  // Leaf pages of the octant table decoded whole by batches so far (a
  // dense batch's walk; a sparse one asks key by key): for tests and
  // diagnostics.
  uint64_t octant_pages_decoded() const { return octant_window_->decodes(); }

  // The leaf holding tick point p; any p (past the root is outside).
  Status locate(Coord p, PointHit* out);
  // Whether tick point p, which no leaf holds, lies above the ground of a
  // mesh built under one (the surface read again, once, as its metadata
  // names it); false for any other mesh.
  bool in_air(Coord p);
  // The ground's elevation at tick point p's column (metres), NaN without one.
  double ground_at(Coord p);
  // The same for n points in any order: sorted by Morton code inside, then
  // answered in one forward walk over the octant table.  out[i] answers p[i].
  Status locate_batch(const Coord* p, size_t n, PointHit* out);
  // The finest level of the aggregate table (query/aggregates.h), -1
  // without one.
  int aggregate_finest() const { return aggregate_finest_; }
  // The summaries of the octants of `level` (0 to aggregate_finest()) that
  // hold the points p[0..n), in any order; out[i] answers p[i].
  Status aggregate_batch(const Coord* p, size_t n, int level, AggregateHit* out);
  // The same worked out from the leaves (any level below 20), octant by
  // octant in key order; once max_leaves leaves have been read no further
  // octant is begun (the one under way is finished), and those not begun
  // are not found.
  Status summarise_batch(const Coord* p, size_t n, int level, uint64_t max_leaves,
                         AggregateHit* out);
  // The nodes at n points (any coordinates; past the far side is no node).
  Status node_at_batch(const Coord* p, size_t n, NodeHit* out);

  // A batch shared among Explorers (threads) is keyed once, cut by key into
  // runs, and each run sorted and walked by one of them, so that each leaf
  // page is read by one only (query/shared_batch.h).  key_batch: (key, i)
  // of the points p[0..n) that can lie in the mesh (node keys with `nodes`,
  // else locate's), in input order.
  static void key_batch(const Coord* p, size_t n, bool nodes, std::vector<KeyedPoint>* order);
  // The walks of a run of a sorted batch: out[i] answers the point of each
  // (key, i) of order[0..n); the other entries of out are left as they are.
  Status locate_sorted(const KeyedPoint* order, size_t n, PointHit* out);
  Status node_at_sorted(const KeyedPoint* order, size_t n, NodeHit* out);

  // Element `id` with its material and (with the mesh) its corners' node ids.
  // InvalidArgument past the last element.
  Status element(uint64_t id, MeshElement* out);
  // Node `id`, with its anchors' ids.
  Status node(uint64_t id, MeshNode* out);

  // The elements across each face (kinds bit 1), edge (bit 2) and corner
  // (bit 3) of element id, direction by direction (kAllDirections' order),
  // each direction's in key order: the one leaf of the element's size or
  // larger that lies across, or the finer leaves that touch the face, edge
  // or corner.  Works on any octree, balanced or not.
  Status neighbors(uint64_t id, unsigned kinds, std::vector<Neighbor>* out);
  // The elements whose closed boxes hold node `id` (up to 8 in a balanced
  // mesh), in id order.
  Status node_elements(uint64_t id, std::vector<NodeElement>* out);
  // The dangling nodes that depend on node `id`, in id order (none unless it
  // is an anchor of some).
  Status depends(uint64_t id, std::vector<MeshNode>* out);

 private:
  Explorer() = default;
  // Fills *order with (key, i) of the valid points, in input order.
  template <typename Valid, typename KeyOf>
  static void key_points(const Coord* p, size_t n, Valid valid, KeyOf key_of,
                         std::vector<KeyedPoint>* order);
  // Clears out[0..n) and sorts the points into order_.
  template <typename Hit, typename Valid, typename KeyOf>
  void sort_points(const Coord* p, size_t n, Hit* out, Valid valid, KeyOf key_of);
  // node_elements() for a node already read.
  Status elements_around(const MeshNode& n, std::vector<NodeElement>* out);
  Status check_node(uint64_t id) const;
  // Visits region r (across direction d of element o): emits the leaf that
  // covers it, or recurses into the children that touch o.
  Status visit_across(const Octant& o, Direction d, const Octant& r, std::vector<Neighbor>* out);

  // The ground, loaded on first need (ground_state_: 0 not yet, 1 loaded,
  // -1 none).
  bool load_ground();
  std::unique_ptr<Surface> surface_;
  Ground ground_;
  int ground_state_ = 0;

  std::unique_ptr<Mesh> mesh_;
  std::unique_ptr<LeafWindow> octant_window_, node_window_, aggregate_window_;
  AggregateLayout aggregate_layout_{false, false};
  int aggregate_finest_ = -1;
  uint64_t batch_bytes_ = 0;
  // Sorting scratch for the batches.
  std::vector<KeyedPoint> order_, scratch_;
};

// "-x", "+y", "-x+z", "+x-y-z": the name of a direction in answers.
std::string direction_name(Direction d);

}  // namespace weaver
