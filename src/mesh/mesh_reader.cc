#include "mesh/mesh_reader.h"

#include <cstdlib>

#include "db/aggregate_table.h"
#include "db/boundary_table.h"
#include "db/model_table_name.h"
#include "db/node_table.h"
#include "db/partition_table.h"
#include "util/metadata_text.h"

namespace weaver {

Status Mesh::open(const std::string& db_dir, uint64_t octant_pool, uint64_t node_pool,
                  std::unique_ptr<Mesh>* out, bool octree_only_ok) {
  std::unique_ptr<Mesh> m(new Mesh());
  WEAVER_RETURN_IF_ERROR(Database::open(db_dir, Database::Mode::kRead, false, &m->db_));
  if (m->db_->has_table(kNodeTable)) {
    WEAVER_RETURN_IF_ERROR(m->db_->open_table(kNodeTable, node_pool, &m->nodes_));
  } else if (!octree_only_ok) {
    return Status::NotFound(db_dir + ": no mesh yet (run 'weaver extract' first)");
  }
  m->model_ = octree_only_ok && !m->db_->has_table(kOctantTable) && m->db_->has_table(kModelTable);
  WEAVER_RETURN_IF_ERROR(
      m->db_->open_table(m->model_ ? kModelTable : kOctantTable, octant_pool, &m->octants_));
  const TableOptions& t = m->octants_->options();
  units_from_metadata(t.metadata, &m->units_);
  m->schema_ = t.schema;
  const Field* vp = m->schema_.find("vp");
  const Field* vs = m->schema_.find("vs");
  const Field* rho = m->schema_.find("rho");
  if (vp != nullptr && vs != nullptr && rho != nullptr) {
    m->vp_ = vp, m->vs_ = vs, m->rho_ = rho;
    const Field* qp = m->schema_.find("qp");
    const Field* qs = m->schema_.find("qs");
    if (qp != nullptr && qs != nullptr) m->qp_ = qp, m->qs_ = qs;
  }
  m->solid_ = m->schema_.find("solid");
  const std::string top = metadata_value(t.metadata, "top_elevation_m");
  if (!top.empty()) m->has_ground_ = true, m->top_elevation_ = std::strtod(top.c_str(), nullptr);
  if (m->db_->has_table(kPartitionTable)) {
    WEAVER_RETURN_IF_ERROR(m->db_->open_table(kPartitionTable, 1 << 20, &m->partition_));
    const std::string& meta = m->partition_->options().metadata;
    m->partition_method_ = metadata_value(meta, "method");
    m->partition_parts_ =
        uint32_t(std::strtoul(metadata_value(meta, "parts").c_str(), nullptr, 10));
    if (m->partition_parts_ == 0) {
      return Status::Corruption(m->partition_->file_name() + ": no part count in its metadata");
    }
  }
  if (m->db_->has_table(kBoundaryTable)) {
    WEAVER_RETURN_IF_ERROR(m->db_->open_table(kBoundaryTable, octant_pool / 8, &m->boundary_));
  }
  if (m->db_->has_table(kAggregateTable)) {
    WEAVER_RETURN_IF_ERROR(m->db_->open_table(kAggregateTable, octant_pool / 8, &m->aggregates_));
  }
  *out = std::move(m);
  return Status::Ok();
}

std::string metadata_value(const std::string& metadata, const std::string& key) {
  return metadata_item(metadata, key);
}

Status Mesh::element(uint64_t id, bool with_nodes, MeshElement* out) {
  if (id >= element_count()) {
    return Status::InvalidArgument("element " + std::to_string(id) + " does not exist (" +
                                   std::to_string(element_count()) + " elements)");
  }
  std::vector<std::byte> payload(octants_->payload_size() + 1);
  uint64_t key = 0;
  WEAVER_RETURN_IF_ERROR(octants_->select(id, &key, payload.data()));
  *out = MeshElement{};
  out->id = id;
  out->octant = octant_from_key(key);
  fill_material(payload.data(), out);
  if (!with_nodes || !has_nodes()) return Status::Ok();
  for (int k = 0; k < 8; ++k) {
    WEAVER_RETURN_IF_ERROR(node_id(octant_corner(out->octant, k), &out->nodes[k]));
  }
  return Status::Ok();
}

Status Mesh::leaf_covering(const Octant& r, bool* found, uint64_t* id, Octant* leaf) {
  uint64_t key = 0;
  WEAVER_RETURN_IF_ERROR(floor_holding(*octants_, r, &key, nullptr, found));
  if (!*found) return Status::Ok();
  *leaf = octant_from_key(key);
  return octants_->rank(key, id);
}

Status Mesh::leaves_inside(const Octant& r, uint64_t* count) {
  uint64_t first = 0, end = 0;
  WEAVER_RETURN_IF_ERROR(octants_->rank(octant_key(r), &first));
  WEAVER_RETURN_IF_ERROR(octants_->rank(octant_key_subtree_end(r), &end));
  *count = end - first;
  return Status::Ok();
}

Status Mesh::node_id(Coord c, uint64_t* id) {
  bool present = false;
  WEAVER_RETURN_IF_ERROR(nodes_->rank_exact(node_key(c), id, &present));
  if (!present) {
    return Status::Corruption("node (" + std::to_string(c.x) + " " + std::to_string(c.y) + " " +
                              std::to_string(c.z) +
                              ") is missing from the node table: run 'weaver extract' again");
  }
  return Status::Ok();
}

Status Mesh::node(uint64_t id, bool with_anchors, MeshNode* out) {
  if (id >= nodes_->size()) {
    return Status::InvalidArgument("node " + std::to_string(id) + " does not exist (" +
                                   std::to_string(nodes_->size()) + " nodes)");
  }
  uint64_t key = 0;
  std::byte kind{};
  WEAVER_RETURN_IF_ERROR(nodes_->select(id, &key, &kind));
  out->id = id;
  out->c = morton_decode(key);
  if (static_cast<uint8_t>(kind) > 2) {
    return Status::Corruption(nodes_->file_name() + ": bad node kind " +
                              std::to_string(static_cast<uint8_t>(kind)));
  }
  out->kind = static_cast<NodeKind>(kind);
  out->anchor_count = 0;
  return with_anchors ? fill_anchors(out) : Status::Ok();
}

void Mesh::fill_material(const std::byte* payload, MeshElement* e) const {
  if (solid_ != nullptr) e->solid = float(RecordSchema::get_double(payload, *solid_));
  if (vp_ == nullptr) return;
  e->vp = float(RecordSchema::get_double(payload, *vp_));
  e->vs = float(RecordSchema::get_double(payload, *vs_));
  e->rho = float(RecordSchema::get_double(payload, *rho_));
  if (qp_ == nullptr) return;
  e->qp = float(RecordSchema::get_double(payload, *qp_));
  e->qs = float(RecordSchema::get_double(payload, *qs_));
}

Status Mesh::fill_anchors(MeshNode* n) {
  Coord a[4];
  n->anchor_count = node_anchors(n->c, n->kind, a);
  for (int i = 0; i < n->anchor_count; ++i) {
    WEAVER_RETURN_IF_ERROR(node_id(a[i], &n->anchors[i]));
  }
  return Status::Ok();
}

Status ElementScan::start(Mesh& mesh, uint64_t first, bool with_nodes) {
  mesh_ = &mesh;
  nodes_ = with_nodes;
  batch_.clear();
  at_ = 0;
  batch_first_ = first;
  uint64_t key = 0;
  if (first > 0 && first < mesh.element_count()) {
    WEAVER_RETURN_IF_ERROR(mesh.octants().select(first, &key, nullptr));
  } else if (first > 0) {
    key = ~uint64_t{0};  // past the end
  }
  status_ = mesh.octants().seek_cursor(key, &cursor_);
  if (status_.ok()) status_ = fill();
  return status_;
}

Status ElementScan::fill() {
  batch_first_ += batch_.size();
  batch_.clear();
  material_.clear();
  at_ = 0;
  MeshElement e;
  while (cursor_.valid() && batch_.size() < kBatch) {
    e.octant = octant_from_key(cursor_.key());
    mesh_->fill_material(cursor_.payload(), &e);
    batch_.push_back(e.octant);
    material_.push_back({e.vp, e.vs, e.rho, e.qp, e.qs, e.solid});
    WEAVER_RETURN_IF_ERROR(cursor_.next());
  }
  if (nodes_) WEAVER_RETURN_IF_ERROR(corners_.resolve(mesh_->nodes(), batch_, &ids_));
  load();
  return Status::Ok();
}

void ElementScan::next() {
  if (++at_ < batch_.size()) return load();
  status_ = fill();
}

void ElementScan::load() {
  if (at_ >= batch_.size()) return;
  e_.id = batch_first_ + at_;
  e_.octant = batch_[at_];
  const std::array<float, 6>& m = material_[at_];
  e_.vp = m[0], e_.vs = m[1], e_.rho = m[2], e_.qp = m[3], e_.qs = m[4], e_.solid = m[5];
  if (nodes_) e_.nodes = ids_[at_];
}

Status NodeScan::start(Mesh& mesh, bool with_anchors) {
  mesh_ = &mesh;
  anchors_ = with_anchors;
  n_ = MeshNode{};
  status_ = mesh.nodes().seek_cursor(0, &cursor_);
  if (status_.ok()) status_ = load();
  return status_;
}

void NodeScan::next() {
  ++n_.id;
  status_ = cursor_.next();
  if (status_.ok()) status_ = load();
}

Status NodeScan::seek(uint64_t id) {
  if (!status_.ok()) return status_;
  if (cursor_.valid() && id >= n_.id && id - n_.id <= kMaxSteps) {
    for (; n_.id < id && cursor_.valid(); ++n_.id) WEAVER_RETURN_IF_ERROR(status_ = cursor_.next());
  } else {
    uint64_t key = 0;
    std::byte kind{};
    WEAVER_RETURN_IF_ERROR(status_ = mesh_->nodes().select(id, &key, &kind));
    WEAVER_RETURN_IF_ERROR(status_ = mesh_->nodes().seek_cursor(key, &cursor_));
  }
  if (!cursor_.valid()) {
    return status_ = Status::InvalidArgument("node " + std::to_string(id) + " does not exist");
  }
  n_.id = id;
  return status_ = load();
}

Status NodeScan::load() {
  if (!cursor_.valid()) return Status::Ok();
  n_.c = morton_decode(cursor_.key());
  const uint8_t raw = static_cast<uint8_t>(cursor_.payload()[0]);
  if (raw > 2) {
    return Status::Corruption(mesh_->nodes().file_name() + ": bad node kind " +
                              std::to_string(raw));
  }
  n_.kind = static_cast<NodeKind>(raw);
  n_.anchor_count = 0;
  if (anchors_) return mesh_->fill_anchors(&n_);
  return Status::Ok();
}

}  // namespace weaver
