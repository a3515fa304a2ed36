#include "cli/query_commands.h"

#include <set>

#include "cli/query_context.h"

namespace weaver::cli {

const char kQueryHelp[] =
    "locate X Y Z            the element holding the point: id, corner, level, edge, node ids\n"
    "                        and material; an element holds corner <= p < corner + edge\n"
    "material X Y Z          vp, vs and rho of the element holding the point (and qp, qs\n"
    "                        when the mesh's model had them)\n"
    "node-at X Y Z           the node at the point, if any\n"
    "  (each of the three also takes --points FILE, or - for stdin: one 'x y z' per\n"
    "   line, answered in input order, one row each, status inside/outside/bad)\n"
    "range X0 Y0 Z0 X1 Y1 Z1 the elements holding any point of the box, bounds included:\n"
    "                        their count, and with --list each one\n"
    "element ID              corner, level, edge, node ids and material of element ID\n"
    "node ID                 coordinate, kind (anchored, edge, face) and anchors of node ID\n"
    "neighbors ID            the elements across the faces of element ID (--faces, the\n"
    "                        default); --edges, --corners, or --all for all three\n"
    "node-elements ID        the elements around node ID, and which corner of each it is\n"
    "depends ID              the dangling nodes that depend on node ID\n"
    "Options:\n"
    "  --units ticks|m       coordinates in and out in ticks (default) or metres\n"
    "  --geo                 locate, material, node-at: points as LON LAT DEPTH (WGS84\n"
    "                        degrees, metres down: below the local ground in a mesh\n"
    "                        built with --surface), in a georeferenced database\n"
    "                        (construct --origin-geo); answers in metres\n"
    "  --z domain|elevation|depth  locate, material, node-at: what a point's z is:\n"
    "                        depth below the domain's top (domain, the default, in\n"
    "                        --units), elevation in metres (up), or metres below the\n"
    "                        local ground (a mesh built with --surface)\n"
    "  --format MODE         text (default), table, json (one document), jsonl (one object\n"
    "                        a line; also ndjson), csv or tsv; --json = --format json\n";

namespace {

const std::set<std::string> kValueOptions = {"format", "units", "points", "memory", "z"};
const std::set<std::string> kFlags = {"json", "list", "faces", "edges", "corners", "all", "geo"};

}  // namespace

int Query::run() {
  if (args.flags.count("json")) s.mode = OutputMode::kJson;
  if (args.values.count("format")) {
    const Status st = parse_output_mode(args.values.at("format"), &s.mode);
    if (!st.ok()) return usage(st.message());
  }
  if (args.values.count("units")) {
    const std::string& u = args.values.at("units");
    if (u != "m" && u != "ticks") return usage("--units is ticks or m, not '" + u + "'");
    s.metres = u == "m";
  }
  const bool point_query = name() == "locate" || name() == "material" || name() == "node-at";
  if (args.values.count("points") && !point_query) {
    return usage("--points is for locate, material and node-at");
  }
  std::string z = "domain";
  if (args.values.count("z")) {
    z = args.values.at("z");
    if (z != "domain" && z != "elevation" && z != "depth")
      return usage("--z is domain, elevation or depth, not '" + z + "'");
    if (!point_query) return usage("--z is for locate, material and node-at");
  }
  if (args.flags.count("geo") || z != "domain") {
    if (!point_query) return usage("--geo is for locate, material and node-at");
    const Status st = to_frame_metres(args.flags.count("geo") != 0, z);
    if (st.is_invalid_argument()) return usage(st.message());
    if (!st.ok()) return fail(st);
  }
  const std::string& q = name();
  if (q == "locate") return run_points(PointQuery::kLocate);
  if (q == "material") return run_points(PointQuery::kMaterial);
  if (q == "node-at") return run_points(PointQuery::kNodeAt);
  if (q == "range") return run_range();
  if (q == "element") return run_element();
  if (q == "node") return run_node();
  if (q == "neighbors") return run_neighbors();
  if (q == "node-elements") return run_node_elements();
  if (q == "depends") return run_depends();
  return usage("unknown query '" + q + "'");
}

Status check_query(const std::vector<std::string>& words) {
  std::vector<char*> argv;
  for (const std::string& w : words) argv.push_back(const_cast<char*>(w.c_str()));
  ParsedArgs a;
  WEAVER_RETURN_IF_ERROR(parse_args(int(argv.size()), argv.data(), 0, kValueOptions, kFlags, &a));
  if (a.positional.empty()) return Status::InvalidArgument("expected a query");
  const std::string& q = a.positional[0];
  const bool point = q == "locate" || q == "material" || q == "node-at";
  const size_t want =
      point          ? (a.values.count("points") ? 0 : 3)
      : q == "range" ? 6
      : q == "element" || q == "node" || q == "neighbors" || q == "node-elements" || q == "depends"
          ? 1
          : SIZE_MAX;
  if (want == SIZE_MAX) return Status::InvalidArgument("unknown query '" + q + "'");
  if (a.positional.size() != want + 1) {
    return Status::InvalidArgument(q + " takes " + std::to_string(want) + " number(s)");
  }
  const bool metres = (a.values.count("units") && a.values.at("units") == "m") ||
                      a.flags.count("geo") || (a.values.count("z") && a.values.at("z") != "domain");
  for (size_t i = 1; i <= want; ++i) {
    double d = 0;
    uint64_t v = 0;
    WEAVER_RETURN_IF_ERROR(metres && want > 1
                               ? parse_double(a.positional[i], "coordinate", &d)
                               : parse_u64(a.positional[i], want == 1 ? "ID" : "coordinate", &v));
  }
  return Status::Ok();
}

int run_query(Explorer& ex, const std::vector<std::string>& words, const QuerySettings& settings,
              std::FILE* out, std::FILE* err, const std::string& who) {
  std::vector<char*> argv;
  for (const std::string& w : words) argv.push_back(const_cast<char*>(w.c_str()));
  ParsedArgs args;
  const Status st = parse_args(int(argv.size()), argv.data(), 0, kValueOptions, kFlags, &args);
  if (!st.ok()) {
    Query q{ex, {}, settings, out, err, who, {nullptr, std::fclose}, {}};
    return q.usage(st.message());
  }
  return run_parsed_query(ex, std::move(args), settings, out, err, who);
}

int run_parsed_query(Explorer& ex, ParsedArgs args, const QuerySettings& settings, std::FILE* out,
                     std::FILE* err, const std::string& who) {
  Query q{ex, std::move(args), settings, out, err, who, {nullptr, std::fclose}, {}};
  if (q.args.positional.empty()) return q.usage("expected a query");
  return q.run();
}

}  // namespace weaver::cli
