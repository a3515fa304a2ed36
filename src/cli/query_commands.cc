#include "cli/query_commands.h"

#include <cmath>
#include <cstring>
#include <memory>
#include <sstream>

#include "cli/point_batch.h"
#include "model/geo_frame.h"
#include "query/octant_query.h"
#include "util/args.h"

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
    "neighbors ID            the elements across the faces of element ID; --edges, --corners\n"
    "                        or --all (faces, edges and corners) for the others\n"
    "node-elements ID        the elements around node ID, and which corner of each it is\n"
    "depends ID              the dangling nodes that depend on node ID\n"
    "Options:\n"
    "  --units ticks|m       coordinates in and out in ticks (default) or metres\n"
    "  --geo                 locate, material, node-at: points as LON LAT DEPTH (WGS84\n"
    "                        degrees, metres down), in a georeferenced database\n"
    "                        (construct --origin-geo); answers in metres\n"
    "  --format MODE         text (default), table, json (one document), jsonl (one object\n"
    "                        a line; also ndjson), csv or tsv; --json = --format json\n";

namespace {

const std::set<std::string> kValueOptions = {"format", "units", "points", "memory"};
const std::set<std::string> kFlags = {"json", "list", "faces", "edges", "corners", "all", "geo"};

struct Query {
  Explorer& ex;
  ParsedArgs args;
  QuerySettings s;
  std::FILE* out;
  std::FILE* err;
  const std::string& who;

  const std::string& name() const { return args.positional[0]; }
  const Units& units() const { return ex.units(); }
  bool text() const { return s.mode == OutputMode::kText; }

  int fail(const Status& st) {
    std::fprintf(err, "%s: %s\n", who.c_str(),
                 st.is_corruption() ? ("corrupt data: " + st.message()).c_str()
                 : st.is_io_error() ? ("I/O error: " + st.message()).c_str()
                                    : st.message().c_str());
    return 1;
  }
  int usage(const std::string& message) {
    std::fprintf(err, "%s: %s (see .help or 'weaver query --help')\n", who.c_str(),
                 message.c_str());
    return 2;
  }

  // Cells of a coordinate and a length, in ticks or metres.
  Cell position(uint32_t tick, int axis) const {
    return s.metres ? Cell::number(units().origin_m[axis] + tick * units().tick_m)
                    : Cell::number(uint64_t(tick));
  }
  Cell length(uint64_t ticks) const {
    return s.metres ? Cell::number(ticks * units().tick_m) : Cell::number(ticks);
  }
  void octant_cells(const Octant& o, std::vector<Cell>* row) const {
    row->push_back(position(o.x, 0));
    row->push_back(position(o.y, 1));
    row->push_back(position(o.z, 2));
    row->push_back(Cell::number(uint64_t(o.level)));
    row->push_back(length(octant_edge(o)));
  }
  static Cell ids(const uint64_t* v, int n) {
    std::vector<std::string> items;
    for (int i = 0; i < n; ++i) items.push_back(std::to_string(v[i]));
    return Cell::list(items);
  }
  // vp, vs, rho (and qp, qs when the mesh has them): the columns, and one
  // element's cells.
  void material_columns(std::vector<std::string>* columns) const {
    columns->insert(columns->end(), {"vp", "vs", "rho"});
    if (ex.mesh().has_q()) columns->insert(columns->end(), {"qp", "qs"});
  }
  void material_cells(const MeshElement& e, std::vector<Cell>* row) const {
    row->push_back(Cell::number(e.vp));
    row->push_back(Cell::number(e.vs));
    row->push_back(Cell::number(e.rho));
    if (!ex.mesh().has_q()) return;
    row->push_back(Cell::number(e.qp));
    row->push_back(Cell::number(e.qs));
  }
  // "vp .. m/s, vs .. m/s, rho .. kg/m^3[, qp .., qs ..]", for text output.
  std::string material_text(const MeshElement& e) const {
    char buf[160];
    int n =
        std::snprintf(buf, sizeof buf, "vp %g m/s, vs %g m/s, rho %g kg/m^3", e.vp, e.vs, e.rho);
    if (ex.mesh().has_q()) std::snprintf(buf + n, sizeof buf - n, ", qp %g, qs %g", e.qp, e.qs);
    return buf;
  }

  // The numbers after the query's name.
  Status numbers(size_t n) {
    if (args.positional.size() != n + 1) {
      return Status::InvalidArgument(name() + " takes " + std::to_string(n) + " number(s)");
    }
    return Status::Ok();
  }
  Status id_argument(uint64_t* id) {
    WEAVER_RETURN_IF_ERROR(numbers(1));
    return parse_u64(args.positional[1], "ID", id);
  }
  // A point: ticks (whole, 0 up to 2^32-1) or metres; metres past the
  // address space become a point that is outside.
  Status point_argument(size_t from, Coord* c) {
    uint32_t* axis[3] = {&c->x, &c->y, &c->z};
    for (int a = 0; a < 3; ++a) {
      const std::string& t = args.positional[from + a];
      if (s.metres) {
        double v = 0;
        WEAVER_RETURN_IF_ERROR(parse_double(t, "coordinate", &v));
        const double tick = std::floor((v - units().origin_m[a]) / units().tick_m);
        *axis[a] = tick >= 0 && tick < 4294967295.0 ? uint32_t(tick) : UINT32_MAX;
        continue;
      }
      uint64_t v = 0;
      WEAVER_RETURN_IF_ERROR(parse_u64(t, "coordinate", &v));
      if (v > UINT32_MAX) return Status::InvalidArgument("coordinate " + t + " is too large");
      *axis[a] = uint32_t(v);
    }
    return Status::Ok();
  }

  int run();
  int run_points(PointQuery q);
  int run_point_text(PointQuery q, Coord c);
  // --geo: the point arguments, or the points file, from LON LAT DEPTH to
  // the frame's metres (and --units m from here on).
  Status to_frame_metres();
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> geo_points{nullptr, std::fclose};
  std::string geo_points_name;  // the file the converted points came from
  int run_range();
  int run_element();
  int run_node();
  int run_neighbors();
  int run_node_elements();
  int run_depends();
  int print(const Table& t) {
    print_table(t, s.mode, out);
    return 0;
  }
};

std::string point_text(Coord c) {
  return std::to_string(c.x) + " " + std::to_string(c.y) + " " + std::to_string(c.z);
}

Status Query::to_frame_metres() {
  if (units().geo.empty()) {
    return Status::NotFound(
        "this database is not georeferenced (construct it with --origin-geo LON,LAT)");
  }
  GeoFrame frame;
  WEAVER_RETURN_IF_ERROR(GeoFrame::parse(units().geo, &frame));
  const GeoTransform g(frame);
  s.metres = true;
  auto convert = [&](double lon, double lat, double depth) {
    double x, y;
    g.to_frame(lon, lat, &x, &y);
    char buf[128];
    std::snprintf(buf, sizeof buf, "%.17g %.17g %.17g", x, y, depth);
    return std::string(buf);
  };
  if (!args.values.count("points")) {
    if (args.positional.size() != 4) return Status::Ok();  // numbers() says what is wrong
    double v[3];
    for (int i = 0; i < 3; ++i) {
      WEAVER_RETURN_IF_ERROR(parse_double(args.positional[i + 1], "coordinate", &v[i]));
    }
    std::istringstream words(convert(v[0], v[1], v[2]));
    for (int i = 1; i <= 3; ++i) words >> args.positional[i];
    return Status::Ok();
  }
  // A points file: each line converted into a scratch file (bounded memory
  // whatever the batch); lines that are not three numbers pass unchanged,
  // for the batch to report in place.
  const std::string& path = args.values.at("points");
  std::FILE* const from_stdin = s.points_stdin != nullptr ? s.points_stdin : stdin;
  std::FILE* in = path == "-" ? from_stdin : std::fopen(path.c_str(), "r");
  if (in == nullptr) return Status::IOError(path + ": " + std::strerror(errno));
  geo_points.reset(std::tmpfile());
  if (!geo_points) return Status::IOError(std::string("a scratch file: ") + std::strerror(errno));
  char line[4096];
  while (std::fgets(line, sizeof line, in)) {
    double lon, lat, depth;
    char extra;
    std::string point = line;
    point = point.substr(0, point.find('#'));
    if (std::sscanf(point.c_str(), "%lf %lf %lf %c", &lon, &lat, &depth, &extra) == 3) {
      std::fprintf(geo_points.get(), "%s\n", convert(lon, lat, depth).c_str());
    } else {
      std::fputs(line, geo_points.get());
    }
  }
  if (in != from_stdin) std::fclose(in);
  std::rewind(geo_points.get());
  s.points_stdin = geo_points.get();
  geo_points_name = path == "-" ? "stdin" : path;
  args.values["points"] = "-";
  return Status::Ok();
}

// locate, material and node-at: a points file, or one point.  Outside text
// mode one point is a batch of one, so both print the same columns.
int Query::run_points(PointQuery q) {
  PointBatchOptions o{q, s.mode, s.metres};
  PointBatchResult r;
  const bool from_file = args.values.count("points") != 0;
  if (from_file && args.positional.size() != 1) {
    return usage(name() + " takes --points or a point, not both");
  }
  if (!from_file) {
    Status st = numbers(3);
    Coord c;
    if (st.ok()) st = point_argument(1, &c);
    if (!st.ok()) return usage(st.message());
    if (text()) return run_point_text(q, c);
    o.one = true;
    const std::string line =
        args.positional[1] + " " + args.positional[2] + " " + args.positional[3] + "\n";
    std::FILE* in = fmemopen(const_cast<char*>(line.data()), line.size(), "r");
    if (in == nullptr) return fail(Status::IOError(std::strerror(errno)));
    st = run_point_batch(ex, in, "point", o, out, err, &r);
    std::fclose(in);
    return st.ok() ? 0 : fail(st);
  }
  const std::string& path = args.values.at("points");
  std::FILE* const from_stdin = s.points_stdin != nullptr ? s.points_stdin : stdin;
  std::FILE* in = path == "-" ? from_stdin : std::fopen(path.c_str(), "r");
  if (in == nullptr) return fail(Status::IOError(path + ": " + std::strerror(errno)));
  const std::string name = !geo_points_name.empty() ? geo_points_name
                           : path == "-"            ? "stdin"
                                                    : path;
  const Status st = run_point_batch(ex, in, name, o, out, err, &r);
  if (in != from_stdin) std::fclose(in);
  if (!st.ok()) return fail(st);
  if (r.bad_lines == 0) return 0;
  std::fprintf(err, "%s: %llu of %llu lines were not points (rows with status 'bad')\n",
               who.c_str(), (unsigned long long)r.bad_lines, (unsigned long long)r.points);
  return 1;
}

int Query::run_point_text(PointQuery q, Coord c) {
  // The point as asked: in ticks, or in metres as typed.
  const std::string asked =
      s.metres ? args.positional[1] + " " + args.positional[2] + " " + args.positional[3] + " m"
               : point_text(c);
  if (q == PointQuery::kNodeAt) {
    NodeHit h;
    const Status st = ex.node_at_batch(&c, 1, &h);
    if (!st.ok()) return fail(st);
    if (!h.found) return std::fprintf(out, "no node at (%s)\n", asked.c_str()), 0;
    args.positional = {"node", std::to_string(h.id)};
    return run_node();
  }
  PointHit h;
  MeshElement e;
  Status st = ex.locate(c, &h);
  if (st.ok() && h.inside) st = ex.element(h.id, &e);
  if (!st.ok()) return fail(st);
  if (q == PointQuery::kMaterial && !ex.mesh().has_material()) {
    return fail(Status::NotFound("this mesh has no material (it was not built from a model)"));
  }
  if (!h.inside) return std::fprintf(out, "point (%s) is outside the domain\n", asked.c_str()), 0;
  if (q == PointQuery::kMaterial) {
    std::fprintf(out, "point (%s): %s (element %llu)\n", asked.c_str(), material_text(e).c_str(),
                 (unsigned long long)e.id);
    return 0;
  }
  std::fprintf(out, "point (%s) is in element %llu: leaf (%s %d), edge %u ticks = %.10g m\n",
               asked.c_str(), (unsigned long long)e.id,
               point_text({e.octant.x, e.octant.y, e.octant.z}).c_str(), e.octant.level,
               octant_edge(e.octant), octant_edge(e.octant) * units().tick_m);
  if (ex.has_nodes()) std::fprintf(out, "  nodes %s\n", plain_text(ids(e.nodes.data(), 8)).c_str());
  if (ex.mesh().has_material()) std::fprintf(out, "  %s\n", material_text(e).c_str());
  return 0;
}

int Query::run_range() {
  Status st = numbers(6);
  Coord lo, hi;
  if (st.ok()) st = point_argument(1, &lo);
  if (st.ok()) st = point_argument(4, &hi);
  if (!st.ok()) return usage(st.message());
  const bool list = args.flags.count("list") != 0;
  Table t;
  t.columns = list ? std::vector<std::string>{"element", "x", "y", "z", "level", "edge"}
                   : std::vector<std::string>{"count"};
  uint64_t count = 0;
  std::function<void(const Octant&, uint64_t)> each;
  if (list) {
    each = [&](const Octant& o, uint64_t id) {
      std::vector<Cell> row{Cell::number(id)};
      octant_cells(o, &row);
      t.rows.push_back(std::move(row));
    };
  }
  st = range_query(ex.mesh().octants(), {lo, hi}, &count, each);
  if (!st.ok()) return fail(st);
  if (!list) t.rows.push_back({Cell::number(count)}), t.one = true;
  if (text() && !list)
    return std::fprintf(out, "%llu leaves intersect the box\n", (unsigned long long)count), 0;
  return print(t);
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
  if (args.flags.count("geo")) {
    if (!point_query) return usage("--geo is for locate, material and node-at");
    const Status st = to_frame_metres();
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

}  // namespace

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
  const bool metres =
      (a.values.count("units") && a.values.at("units") == "m") || a.flags.count("geo");
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
  Query q{ex, {}, settings, out, err, who, {nullptr, std::fclose}, {}};
  const Status st = parse_args(int(argv.size()), argv.data(), 0, kValueOptions, kFlags, &q.args);
  if (!st.ok()) return q.usage(st.message());
  if (q.args.positional.empty()) return q.usage("expected a query");
  return q.run();
}

}  // namespace weaver::cli
