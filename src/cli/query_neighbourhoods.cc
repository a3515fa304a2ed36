// The neighbourhood queries: neighbors, node-elements and depends.
#include <cstring>
#include <sstream>

#include "cli/query_context.h"

namespace weaver::cli {

int Query::run_neighbors() {
  const char* kinds[] = {"faces", "edges", "corners", "all"};
  unsigned mask = 0;
  for (int k = 0; k < 4; ++k) {
    if (args.flags.count(kinds[k])) mask |= k == 3 ? 0xe : 1u << (k + 1);
  }
  if (mask == 0) mask = 1u << 1;
  uint64_t id = 0;
  std::vector<Neighbor> got;
  Status st = id_argument(&id);
  if (!st.ok()) return usage(st.message());
  st = ex.neighbors(id, mask, &got);
  if (!st.ok()) return fail(st);
  static const char* const kKind[] = {"", "face", "edge", "corner"};
  Table t;
  t.columns = {"across", "kind", "element", "x", "y", "z", "level", "edge"};
  for (const Neighbor& n : got) {
    std::vector<Cell> row{Cell::string(direction_name(n.dir)), Cell::string(kKind[n.dir.nonzero()]),
                          Cell::number(n.id)};
    octant_cells(n.octant, &row);
    t.rows.push_back(std::move(row));
  }
  return print(t);
}

int Query::run_node_elements() {
  uint64_t id = 0;
  std::vector<NodeElement> got;
  Status st = id_argument(&id);
  if (!st.ok()) return usage(st.message());
  st = ex.node_elements(id, &got);
  if (!st.ok()) return fail(st);
  Table t;
  t.columns = {"element", "corner", "x", "y", "z", "level", "edge"};
  for (const NodeElement& e : got) {
    std::vector<Cell> row{Cell::number(e.id),
                          e.corner < 0 ? Cell::string("hangs") : Cell::number(uint64_t(e.corner))};
    octant_cells(e.octant, &row);
    t.rows.push_back(std::move(row));
  }
  return print(t);
}

int Query::run_depends() {
  uint64_t id = 0;
  std::vector<MeshNode> got;
  Status st = id_argument(&id);
  if (!st.ok()) return usage(st.message());
  st = ex.depends(id, &got);
  if (!st.ok()) return fail(st);
  Table t;
  t.columns = {"node", "kind", "x", "y", "z", "anchors"};
  for (const MeshNode& n : got) {
    t.rows.push_back({Cell::number(n.id), Cell::string(node_kind_name(n.kind)), position(n.c.x, 0),
                      position(n.c.y, 1), position(n.c.z, 2),
                      ids(n.anchors.data(), n.anchor_count)});
  }
  return print(t);
}

}  // namespace weaver::cli
