// Read access to an extracted mesh: the octant and node tables of one
// committed state, the ids of an element's corners and of a dangling node's
// anchors, the material of an element, and scans of both tables in id order.
// What the transform (export) and the query layer share.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "db/database.h"
#include "db/octant_table.h"
#include "mesh/corner_batch.h"
#include "mesh/part_map.h"
#include "schema/node.h"
#include "schema/octant.h"
#include "schema/record_schema.h"
#include "schema/status.h"
#include "storage/btree.h"

namespace weaver {

struct MeshElement {
  uint64_t id = 0;
  Octant octant;
  std::array<uint64_t, 8> nodes{};  // node ids of corners 0..7 (x fastest)
  float vp = 0, vs = 0, rho = 0;    // when the mesh has material
  float qp = 0, qs = 0;             // when its material has them
  float solid = 1;                  // the share below the ground (has_ground())
};

struct MeshNode {
  uint64_t id = 0;
  Coord c;
  NodeKind kind = NodeKind::kAnchored;
  int anchor_count = 0;
  std::array<uint64_t, 4> anchors{};  // node ids, ascending
};

class Mesh {
 public:
  // Opens the mesh of db_dir read-only.  NotFound when there is no node table
  // yet (the octree was never extracted), unless octree_only_ok: then the
  // octree alone is open and has_nodes() is false.  With octree_only_ok a
  // model database (`weaver model import`: no octant table, a model table)
  // opens too, its cells as the octree's leaves (is_model()).
  static Status open(const std::string& db_dir, uint64_t octant_pool, uint64_t node_pool,
                     std::unique_ptr<Mesh>* out, bool octree_only_ok = false);

  BTree& octants() { return *octants_; }
  BTree& nodes() { return *nodes_; }  // REQUIRES: has_nodes()
  bool has_nodes() const { return nodes_ != nullptr; }
  // Whether the leaves are a model database's cells (open's octree_only_ok).
  bool is_model() const { return model_; }
  uint64_t element_count() const { return octants_->size(); }
  uint64_t node_count() const { return nodes_ ? nodes_->size() : 0; }
  const Units& units() const { return units_; }
  // Whether the octant table carries vp, vs and rho (a mesh built from a model).
  bool has_material() const { return vp_ != nullptr; }
  // Whether it carries qp and qs too (a model with attenuation).
  bool has_q() const { return qp_ != nullptr; }
  // Whether the mesh follows a ground surface (construct --surface): air cut
  // away, each element's solid fraction in its 'solid' column.
  bool has_solid() const { return solid_ != nullptr; }
  // The elevation of z = 0 (metres): 0 unless the mesh was built with a
  // ground or --top-elevation.
  double top_elevation() const { return top_elevation_; }
  bool has_ground() const { return has_ground_; }
  // The stored partition (`weaver partition`), if any: its parts, method
  // ("sfc" or "graph") and map.
  bool has_partition() const { return partition_ != nullptr; }
  uint32_t partition_parts() const { return partition_parts_; }
  const std::string& partition_method() const { return partition_method_; }
  Status partition(PartMap* out) { return PartMap::of_table(*partition_, partition_parts_, out); }
  BTree& partition_table() { return *partition_; }
  // The boundary table (`weaver boundary`, db/boundary_table.h), if any.
  bool has_boundary() const { return boundary_ != nullptr; }
  BTree& boundary() { return *boundary_; }
  // The aggregate table (`weaver aggregate`, query/aggregates.h), if any.
  bool has_aggregates() const { return aggregates_ != nullptr; }
  BTree& aggregates() { return *aggregates_; }

  // Element `id` (InvalidArgument past the last) with its material and,
  // when with_nodes and the mesh has nodes, its corners' node ids.
  Status element(uint64_t id, bool with_nodes, MeshElement* out);
  // The leaf that holds all of region r, with its id; *found false when the
  // leaves inside r are finer than r, or r lies in a hole of the domain.
  Status leaf_covering(const Octant& r, bool* found, uint64_t* id, Octant* leaf);
  // How many leaves lie inside region r.
  Status leaves_inside(const Octant& r, uint64_t* count);
  // The id of the node at c; Corruption naming c when the node table lacks it.
  Status node_id(Coord c, uint64_t* id);
  // The node with this id (InvalidArgument past the last), with its anchors' ids.
  Status node(uint64_t id, bool with_anchors, MeshNode* out);
  // The element's vp, vs, rho (and qp, qs) from its octant table payload
  // (zeros for what the mesh does not have).
  void fill_material(const std::byte* payload, MeshElement* e) const;
  // A node's anchors, from its coordinate and kind.
  Status fill_anchors(MeshNode* n);

 private:
  Mesh() = default;
  std::unique_ptr<Database> db_;
  std::unique_ptr<BTree> octants_, nodes_;
  Units units_;
  RecordSchema schema_;
  const Field *vp_ = nullptr, *vs_ = nullptr, *rho_ = nullptr, *qp_ = nullptr, *qs_ = nullptr;
  const Field* solid_ = nullptr;
  std::unique_ptr<BTree> boundary_;
  double top_elevation_ = 0;
  bool has_ground_ = false;
  std::unique_ptr<BTree> partition_, aggregates_;
  bool model_ = false;
  uint32_t partition_parts_ = 0;
  std::string partition_method_;
};

// "key=value" of ';'-separated metadata text ("" if absent).
std::string metadata_value(const std::string& metadata, const std::string& key);

// Scans read as leveldb's iterators do:
//   ElementScan scan;
//   WEAVER_RETURN_IF_ERROR(scan.start(mesh));
//   for (; scan.valid(); scan.next()) { ... }
//   WEAVER_RETURN_IF_ERROR(scan.status());

// The elements from `first` on, in id order, with material and (unless
// with_nodes is false, which saves 8 lookups an element) corner ids.
// Corner ids are found a batch of elements at a time (mesh/corner_batch.h).
class ElementScan {
 public:
  Status start(Mesh& mesh, uint64_t first = 0, bool with_nodes = true);
  bool valid() const { return status_.ok() && at_ < batch_.size(); }
  const MeshElement& element() const { return e_; }  // REQUIRES: valid()
  // Moves on; an error ends the scan and stays in status().
  void next();
  // Check after the loop: whether the scan ended at the end or on an error.
  const Status& status() const { return status_; }

 private:
  static constexpr size_t kBatch = 4096;
  // Reads the next batch of elements (with their corners) from the cursor.
  Status fill();
  void load();

  Status status_;
  Mesh* mesh_ = nullptr;
  bool nodes_ = true;
  BTreeCursor cursor_;
  uint64_t batch_first_ = 0;                    // the id of batch_[0]
  std::vector<Octant> batch_;                   // the elements read ahead
  std::vector<std::array<float, 6>> material_;  // their vp, vs, rho, qp, qs, solid
  std::vector<std::array<uint64_t, 8>> ids_;    // their corners' ids
  size_t at_ = 0;                               // batch_[at_] is e_
  CornerBatch corners_;
  MeshElement e_;
};

// The nodes in id order, with kind and (if wanted) anchor ids.
class NodeScan {
 public:
  Status start(Mesh& mesh, bool with_anchors);
  bool valid() const { return status_.ok() && cursor_.valid(); }
  const MeshNode& node() const { return n_; }  // REQUIRES: valid()
  void next();                                 // as ElementScan's
  // Moves to node `id`: a few cursor steps when it is a little ahead (the
  // nodes of a part are nearly a run of ids), else a search.
  Status seek(uint64_t id);
  const Status& status() const { return status_; }

 private:
  // Farther than this many nodes ahead, a search is cheaper than steps.
  static constexpr uint64_t kMaxSteps = 64;
  Status status_;
  Status load();
  Mesh* mesh_ = nullptr;
  bool anchors_ = false;
  BTreeCursor cursor_;
  MeshNode n_;
};

}  // namespace weaver
