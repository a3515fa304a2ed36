#include <array>
#include <cstdio>
#include <functional>

#include "cli/cli.h"
#include "db/database.h"
#include "db/node_table.h"
#include "db/octant_table.h"
#include "query/mesh_query.h"
#include "query/octant_query.h"

namespace weaver::cli {
namespace {

constexpr char kUsage[] =
    "usage: weaver query DB locate X Y Z [--json]\n"
    "       weaver query DB range X0 Y0 Z0 X1 Y1 Z1 [--list] [--json]\n"
    "       weaver query DB element ID [--json]\n"
    "       weaver query DB node ID [--json]\n"
    "       weaver query DB node-at X Y Z [--json]\n"
    "\n"
    "locate   the element that contains tick point (X,Y,Z), with its node ids once\n"
    "         the mesh is extracted, or 'outside the domain'; an element holds the\n"
    "         points corner <= p < corner + edge.\n"
    "range    the elements holding any point of the box X0..X1, Y0..Y1, Z0..Z1\n"
    "         (ticks, bounds included): their count, and with --list each one.\n"
    "element  corner, level, edge and the 8 node ids of element ID.\n"
    "node     coordinate, kind (anchored, edge, face) and anchors of node ID.\n"
    "node-at  the node at tick point (X,Y,Z) (up to 1048576, the far side).\n"
    "Coordinates are in ticks; lengths are also shown in metres.\n"
    "  --memory BYTES  memory budget (default 256M): the octant and node table\n"
    "                  caches, half each\n";

std::string octant_text(const Octant& o) {
  return std::to_string(o.x) + " " + std::to_string(o.y) + " " + std::to_string(o.z) + " " +
         std::to_string(o.level);
}

std::string octant_json(const Octant& o, uint64_t id) {
  return "{\"id\": " + std::to_string(id) + ", \"x\": " + std::to_string(o.x) +
         ", \"y\": " + std::to_string(o.y) + ", \"z\": " + std::to_string(o.z) +
         ", \"level\": " + std::to_string(o.level) +
         ", \"edge\": " + std::to_string(octant_edge(o)) + "}";
}

// Coordinates up to `max` (kRootEdge - 1 for pixels, kRootEdge for nodes).
Status parse_coords(const std::vector<std::string>& p, size_t from, size_t n, uint64_t max,
                    std::vector<uint32_t>* out) {
  for (size_t i = 0; i < n; ++i) {
    uint64_t v = 0;
    WEAVER_RETURN_IF_ERROR(parse_u64(p[from + i], "coordinate", &v));
    if (v > max) {
      return Status::InvalidArgument("coordinate " + p[from + i] + " is outside [0, " +
                                     std::to_string(max) + "]");
    }
    out->push_back(static_cast<uint32_t>(v));
  }
  return Status::Ok();
}

std::string ids_json(const uint64_t* ids, int n) {
  std::string s = "[";
  for (int i = 0; i < n; ++i) s += (i ? ", " : "") + std::to_string(ids[i]);
  return s + "]";
}

std::string ids_text(const uint64_t* ids, int n) {
  std::string s;
  for (int i = 0; i < n; ++i) s += (i ? " " : "") + std::to_string(ids[i]);
  return s;
}

bool in_root(const std::vector<uint32_t>& c, uint32_t limit) {
  return c[0] <= limit && c[1] <= limit && c[2] <= limit;
}

int run_locate(BTree& t, BTree* nodes, const Units& u, const std::vector<uint32_t>& c, bool json) {
  LocateResult r;
  Status st = in_root(c, kRootEdge - 1) ? locate(t, {c[0], c[1], c[2]}, &r) : Status::Ok();
  std::array<uint64_t, 8> ids{};
  if (st.ok() && r.inside && nodes != nullptr) st = element_nodes(*nodes, r.leaf, &ids);
  if (!st.ok()) return report("query", st);
  const std::string pt =
      std::to_string(c[0]) + " " + std::to_string(c[1]) + " " + std::to_string(c[2]);
  if (json) {
    std::printf("{\"point\": [%u, %u, %u], \"inside\": %s", c[0], c[1], c[2],
                r.inside ? "true" : "false");
    if (r.inside) std::printf(", \"element\": %s", octant_json(r.leaf, r.element_id).c_str());
    if (r.inside && nodes != nullptr)
      std::printf(", \"nodes\": %s", ids_json(ids.data(), 8).c_str());
    std::printf("}\n");
  } else if (!r.inside) {
    std::printf("point (%s) is outside the domain\n", pt.c_str());
  } else {
    std::printf("point (%s) is in element %llu: leaf (%s), edge %u ticks = %.10g m\n", pt.c_str(),
                (unsigned long long)r.element_id, octant_text(r.leaf).c_str(), octant_edge(r.leaf),
                octant_edge(r.leaf) * u.tick_m);
    if (nodes != nullptr) std::printf("  nodes %s\n", ids_text(ids.data(), 8).c_str());
  }
  return 0;
}

int run_element(BTree& t, BTree* nodes, const Units& u, uint64_t id, bool json) {
  ElementInfo e;
  const Status st = element_by_id(t, nodes, id, &e);
  if (!st.ok()) return report("query", st);
  const uint32_t edge = octant_edge(e.octant);
  if (json) {
    std::printf("{\"element\": %s", octant_json(e.octant, e.id).c_str());
    if (e.has_nodes) std::printf(", \"nodes\": %s", ids_json(e.nodes.data(), 8).c_str());
    std::printf("}\n");
    return 0;
  }
  std::printf("element %llu: corner (%u %u %u), level %d, edge %u ticks = %.10g m\n",
              (unsigned long long)e.id, e.octant.x, e.octant.y, e.octant.z, e.octant.level, edge,
              edge * u.tick_m);
  if (e.has_nodes) std::printf("  nodes %s\n", ids_text(e.nodes.data(), 8).c_str());
  return 0;
}

int print_node(const NodeInfo& n, const Units& u, bool json) {
  if (json) {
    std::printf(
        "{\"id\": %llu, \"x\": %u, \"y\": %u, \"z\": %u, \"kind\": \"%s\", "
        "\"anchors\": %s}\n",
        (unsigned long long)n.id, n.c.x, n.c.y, n.c.z, node_kind_name(n.kind),
        ids_json(n.anchors.data(), n.anchor_count).c_str());
    return 0;
  }
  std::printf("node %llu: (%u %u %u) ticks = (%.10g %.10g %.10g) m, %s", (unsigned long long)n.id,
              n.c.x, n.c.y, n.c.z, u.origin_m[0] + n.c.x * u.tick_m,
              u.origin_m[1] + n.c.y * u.tick_m, u.origin_m[2] + n.c.z * u.tick_m,
              node_kind_name(n.kind));
  if (n.anchor_count > 0) {
    std::printf(", depends on nodes %s", ids_text(n.anchors.data(), n.anchor_count).c_str());
  }
  std::printf("\n");
  return 0;
}

int run_range(BTree& t, const std::vector<uint32_t>& c, bool list, bool json) {
  const TickBox box{{c[0], c[1], c[2]}, {c[3], c[4], c[5]}};
  uint64_t count = 0;
  std::string items;
  auto on_leaf = [&](const Octant& o, uint64_t id) {
    if (json) {
      items += (items.empty() ? "" : ", ") + octant_json(o, id);
    } else {
      std::printf("%llu %s\n", (unsigned long long)id, octant_text(o).c_str());
    }
  };
  if (!json && list) std::printf("# id x y z level\n");
  std::function<void(const Octant&, uint64_t)> emit;
  if (list) emit = on_leaf;
  const Status st = range_query(t, box, &count, emit);
  if (!st.ok()) return report("query", st);
  if (json) {
    std::printf("{\"count\": %llu%s%s%s}\n", (unsigned long long)count,
                list ? ", \"leaves\": [" : "", items.c_str(), list ? "]" : "");
  } else {
    std::printf("%llu leaves intersect the box\n", (unsigned long long)count);
  }
  return 0;
}

}  // namespace

int cmd_query(int argc, char** argv) {
  ParsedArgs args;
  Status st = parse_args(argc, argv, 2, {"memory"}, {"json", "list"}, &args);
  if (args.help) return std::fputs(kUsage, stdout), 0;
  if (!st.ok()) return usage_error("query", st.message(), kUsage);
  const auto& p = args.positional;
  if (p.size() < 2) return usage_error("query", "expected DB and a query", kUsage);
  const std::string& kind = p[1];
  const size_t want = kind == "locate" || kind == "node-at" ? 3
                      : kind == "range"                     ? 6
                      : kind == "element" || kind == "node" ? 1
                                                            : 0;
  if (want == 0) return usage_error("query", "unknown query '" + kind + "'", kUsage);
  if (p.size() != 2 + want) {
    return usage_error("query", kind + " takes " + std::to_string(want) + " number(s)", kUsage);
  }
  std::vector<uint32_t> c;
  uint64_t id = 0;
  MemoryBudget memory;
  if (want == 1) {
    st = parse_u64(p[2], "ID", &id);
  } else {
    // A point past the root is a fine question for locate and node-at (the
    // answer is "outside" / "no node"); a box must lie in the address space.
    st = parse_coords(p, 2, want, kind == "range" ? kRootEdge - 1 : UINT32_MAX, &c);
  }
  if (st.ok()) st = memory_option(args, &memory);
  if (!st.ok()) return usage_error("query", st.message(), kUsage);
  std::unique_ptr<Database> db;
  std::unique_ptr<BTree> t, nodes;
  st = Database::open(p[0], Database::Mode::kRead, false, &db);
  const QueryMemory shares(memory);
  if (st.ok()) st = db->open_table(kOctantTable, shares.octant_pool, &t);
  if (st.ok() && db->has_table(kNodeTable))
    st = db->open_table(kNodeTable, shares.node_pool, &nodes);
  if (st.ok() && !nodes && (kind == "node" || kind == "node-at")) {
    st = Status::NotFound(p[0] + ": no mesh yet (run 'weaver extract' first)");
  }
  if (!st.ok()) return report("query", st);
  Units u;
  units_from_metadata(t->options().metadata, &u);
  const bool json = args.flags.count("json") != 0;
  if (kind == "locate") return run_locate(*t, nodes.get(), u, c, json);
  if (kind == "range") return run_range(*t, c, args.flags.count("list") != 0, json);
  if (kind == "element") return run_element(*t, nodes.get(), u, id, json);
  NodeInfo n;
  if (kind == "node") {
    st = node_by_id(*nodes, id, &n);
    if (!st.ok()) return report("query", st);
    return print_node(n, u, json);
  }
  bool found = false;
  if (in_root(c, kRootEdge)) st = node_at(*nodes, {c[0], c[1], c[2]}, &n, &found);
  if (!st.ok()) return report("query", st);
  if (!found) {
    if (json) {
      std::printf("{\"point\": [%u, %u, %u], \"node\": null}\n", c[0], c[1], c[2]);
    } else {
      std::printf("no node at (%u %u %u)\n", c[0], c[1], c[2]);
    }
    return 0;
  }
  return print_node(n, u, json);
}

}  // namespace weaver::cli
