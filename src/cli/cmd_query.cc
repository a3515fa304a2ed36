#include <cstdio>
#include <functional>

#include "cli/cli.h"
#include "db/database.h"
#include "db/octant_table.h"
#include "query/octant_query.h"

namespace weaver::cli {
namespace {

constexpr char kUsage[] =
    "usage: weaver query DB locate X Y Z [--json]\n"
    "       weaver query DB range X0 Y0 Z0 X1 Y1 Z1 [--list] [--json]\n"
    "\n"
    "locate  the leaf (element) that contains tick point (X,Y,Z), or 'outside the\n"
    "        domain'; a leaf holds the points corner <= p < corner + edge.\n"
    "range   the leaves holding any point of the box X0..X1, Y0..Y1, Z0..Z1\n"
    "        (ticks, bounds included): their count, and with --list each leaf.\n"
    "  --memory BYTES  buffer pool size (default 256M)\n";

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

Status parse_coords(const std::vector<std::string>& p, size_t from, size_t n,
                    std::vector<uint32_t>* out) {
  for (size_t i = 0; i < n; ++i) {
    uint64_t v = 0;
    WEAVER_RETURN_IF_ERROR(parse_u64(p[from + i], "coordinate", &v));
    if (v >= kRootEdge) {
      return Status::InvalidArgument("coordinate " + p[from + i] +
                                     " is outside the address space [0, 1048576)");
    }
    out->push_back(static_cast<uint32_t>(v));
  }
  return Status::Ok();
}

int run_locate(BTree& t, const Units& u, const std::vector<uint32_t>& c, bool json) {
  LocateResult r;
  const Status st = locate(t, {c[0], c[1], c[2]}, &r);
  if (!st.ok()) return report("query", st);
  const std::string pt = std::to_string(c[0]) + " " + std::to_string(c[1]) + " " +
                         std::to_string(c[2]);
  if (json) {
    std::printf("{\"point\": [%u, %u, %u], \"inside\": %s", c[0], c[1], c[2],
                r.inside ? "true" : "false");
    if (r.inside) std::printf(", \"element\": %s", octant_json(r.leaf, r.element_id).c_str());
    std::printf("}\n");
  } else if (!r.inside) {
    std::printf("point (%s) is outside the domain\n", pt.c_str());
  } else {
    std::printf("point (%s) is in element %llu: leaf (%s), edge %u ticks = %g m\n", pt.c_str(),
                (unsigned long long)r.element_id, octant_text(r.leaf).c_str(),
                octant_edge(r.leaf), octant_edge(r.leaf) * u.tick_m);
  }
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
  const size_t want = kind == "locate" ? 3 : kind == "range" ? 6 : 0;
  if (want == 0) return usage_error("query", "unknown query '" + kind + "'", kUsage);
  if (p.size() != 2 + want) {
    return usage_error("query", kind + " takes " + std::to_string(want) + " coordinates", kUsage);
  }
  std::vector<uint32_t> c;
  uint64_t memory = 0;
  st = parse_coords(p, 2, want, &c);
  if (st.ok()) st = memory_option(args, &memory);
  if (!st.ok()) return usage_error("query", st.message(), kUsage);
  std::unique_ptr<Database> db;
  std::unique_ptr<BTree> t;
  st = Database::open(p[0], Database::Mode::kRead, false, &db);
  if (st.ok()) st = db->open_table(kOctantTable, memory, &t);
  if (!st.ok()) return report("query", st);
  Units u;
  units_from_metadata(t->options().metadata, &u);
  const bool json = args.flags.count("json") != 0;
  if (kind == "locate") return run_locate(*t, u, c, json);
  return run_range(*t, c, args.flags.count("list") != 0, json);
}

}  // namespace weaver::cli
