// The queries of a box or an id: range, element and node.
#include <cstring>
#include <sstream>

#include "cli/query_context.h"
#include "mesh/octant_query.h"

namespace weaver::cli {

int Query::run_range() {
  Status st = numbers(6);
  Coord lo, hi;
  if (st.ok()) st = point_argument(1, &lo);
  if (st.ok()) st = point_argument(4, &hi);
  if (!st.ok()) return usage(st.message());
  uint64_t count = 0;
  st = range_query(ex.mesh().octants(), {lo, hi}, &count, nullptr);
  if (!st.ok()) return fail(st);
  if (s.list_count != nullptr) *s.list_count = count;
  if (!args.flags.count("list")) {
    if (text())
      return std::fprintf(out, "%llu leaves intersect the box\n", (unsigned long long)count), 0;
    return print(Table{{"count"}, {{Cell::number(count)}}, true});
  }
  // Streamed a row at a time: a box may hold the whole mesh.
  TableStream rows(s.mode, {"element", "x", "y", "z", "level", "edge"}, out);
  uint64_t next = UINT64_MAX;
  st = range_page(
      ex.mesh().octants(), {lo, hi}, s.list_from, s.list_limit,
      [&](const Octant& o, uint64_t id) {
        std::vector<Cell> row{Cell::number(id)};
        octant_cells(o, &row);
        rows.row(std::move(row));
      },
      &next);
  if (!st.ok()) return fail(st);
  rows.finish();
  if (s.list_next != nullptr) *s.list_next = next;
  return 0;
}

int Query::run_element() {
  uint64_t id = 0;
  MeshElement e;
  Status st = id_argument(&id);
  if (!st.ok()) return usage(st.message());
  st = ex.element(id, &e);
  if (!st.ok()) return fail(st);
  const bool nodes = ex.has_nodes(), material = ex.mesh().has_material();
  if (text()) {
    const uint32_t edge = octant_edge(e.octant);
    std::fprintf(out, "element %llu: corner (%s), level %d, edge %u ticks = %.10g m\n",
                 (unsigned long long)id, point_text({e.octant.x, e.octant.y, e.octant.z}).c_str(),
                 e.octant.level, edge, edge * units().tick_m);
    if (nodes) std::fprintf(out, "  nodes %s\n", plain_text(ids(e.nodes.data(), 8)).c_str());
    if (material) std::fprintf(out, "  %s\n", material_text(e).c_str());
    return 0;
  }
  Table t;
  t.columns = {"element", "x", "y", "z", "level", "edge"};
  t.one = true;
  std::vector<Cell> row{Cell::number(id)};
  octant_cells(e.octant, &row);
  if (nodes) t.columns.push_back("nodes"), row.push_back(ids(e.nodes.data(), 8));
  if (material) material_columns(&t.columns), material_cells(e, &row);
  t.rows.push_back(row);
  return print(t);
}

int Query::run_node() {
  uint64_t id = 0;
  MeshNode n;
  Status st = id_argument(&id);
  if (!st.ok()) return usage(st.message());
  st = ex.node(id, &n);
  if (!st.ok()) return fail(st);
  if (text()) {
    const Units& u = units();
    std::fprintf(out, "node %llu: (%s) ticks = (%.10g %.10g %.10g) m, %s", (unsigned long long)id,
                 point_text(n.c).c_str(), u.origin_m[0] + n.c.x * u.tick_m,
                 u.origin_m[1] + n.c.y * u.tick_m, u.origin_m[2] + n.c.z * u.tick_m,
                 node_kind_name(n.kind));
    if (n.anchor_count > 0) {
      std::fprintf(out, ", depends on nodes %s",
                   plain_text(ids(n.anchors.data(), n.anchor_count)).c_str());
    }
    std::fprintf(out, "\n");
    return 0;
  }
  Table t;
  t.columns = {"node", "x", "y", "z", "kind", "anchors"};
  t.one = true;
  t.rows.push_back({Cell::number(id), position(n.c.x, 0), position(n.c.y, 1), position(n.c.z, 2),
                    Cell::string(node_kind_name(n.kind)), ids(n.anchors.data(), n.anchor_count)});
  return print(t);
}

}  // namespace weaver::cli
