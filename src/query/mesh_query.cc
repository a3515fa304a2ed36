#include "query/mesh_query.h"

#include <string>

namespace weaver {
namespace {

std::string coord_text(Coord c) {
  return "(" + std::to_string(c.x) + " " + std::to_string(c.y) + " " + std::to_string(c.z) + ")";
}

Status id_of(BTree& nodes, Coord c, uint64_t* id) {
  bool present = false;
  WEAVER_RETURN_IF_ERROR(nodes.rank_exact(node_key(c), id, &present));
  if (!present) {
    return Status::Corruption("node " + coord_text(c) +
                              " is missing from the node table: run 'weaver extract' again");
  }
  return Status::Ok();
}

Status describe_node(BTree& nodes, uint64_t id, uint64_t key, uint8_t kind, NodeInfo* out) {
  if (kind > 2) return Status::Corruption(nodes.file_name() + ": bad node kind");
  out->id = id;
  out->c = morton_decode(key);
  out->kind = static_cast<NodeKind>(kind);
  Coord anchors[4];
  out->anchor_count = node_anchors(out->c, out->kind, anchors);
  for (int i = 0; i < out->anchor_count; ++i) {
    WEAVER_RETURN_IF_ERROR(id_of(nodes, anchors[i], &out->anchors[i]));
  }
  return Status::Ok();
}

}  // namespace

Status element_nodes(BTree& nodes, const Octant& o, std::array<uint64_t, 8>* ids) {
  for (int k = 0; k < 8; ++k) WEAVER_RETURN_IF_ERROR(id_of(nodes, octant_corner(o, k), &(*ids)[k]));
  return Status::Ok();
}

Status element_by_id(BTree& octants, BTree* nodes, uint64_t id, ElementInfo* out) {
  if (id >= octants.size()) {
    return Status::InvalidArgument("element " + std::to_string(id) + " does not exist (" +
                                   std::to_string(octants.size()) + " elements)");
  }
  uint64_t key = 0;
  WEAVER_RETURN_IF_ERROR(octants.select(id, &key, nullptr));
  out->id = id;
  out->octant = octant_from_key(key);
  out->has_nodes = nodes != nullptr;
  if (nodes != nullptr) WEAVER_RETURN_IF_ERROR(element_nodes(*nodes, out->octant, &out->nodes));
  return Status::Ok();
}

Status node_by_id(BTree& nodes, uint64_t id, NodeInfo* out) {
  if (id >= nodes.size()) {
    return Status::InvalidArgument("node " + std::to_string(id) + " does not exist (" +
                                   std::to_string(nodes.size()) + " nodes)");
  }
  uint64_t key = 0;
  std::byte kind{};
  WEAVER_RETURN_IF_ERROR(nodes.select(id, &key, &kind));
  return describe_node(nodes, id, key, static_cast<uint8_t>(kind), out);
}

Status node_at(BTree& nodes, Coord c, NodeInfo* out, bool* found) {
  *found = false;
  if (!node_is_valid(c)) {
    return Status::InvalidArgument("point " + coord_text(c) +
                                   " is beyond the far side of the root (1048576)");
  }
  uint64_t id = 0;
  bool present = false;
  WEAVER_RETURN_IF_ERROR(nodes.rank_exact(node_key(c), &id, &present));
  if (!present) return Status::Ok();
  *found = true;
  return node_by_id(nodes, id, out);
}

}  // namespace weaver
