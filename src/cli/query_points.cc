// The point queries: locate, material and node-at, of one point or a
// points file, in ticks, metres or (--geo) longitude and latitude.
#include <cstring>
#include <sstream>

#include "cli/query_context.h"
#include "model/geo_frame.h"

namespace weaver::cli {

Status Query::to_frame_metres(bool geo, const std::string& z) {
  if (geo && units().geo.empty()) {
    return Status::NotFound(
        "this database is not georeferenced (construct it with --origin-geo LON,LAT)");
  }
  GeoFrame frame;
  if (geo) WEAVER_RETURN_IF_ERROR(GeoFrame::parse(units().geo, &frame));
  const GeoTransform g(frame);
  const bool grounded = ex.mesh().has_ground();
  // --geo's depth is below the local ground where the mesh has one.
  const std::string zmode = geo && z == "domain" ? (grounded ? "depth" : "domain") : z;
  if (zmode == "depth" && !grounded)
    return Status::InvalidArgument("--z depth needs a mesh built with --surface");
  const double top = ex.mesh().top_elevation();
  const Units& u = units();
  s.metres = true;
  auto convert = [&](double a, double b, double c) {
    double x = a, y = b;
    if (geo) g.to_frame(a, b, &x, &y);
    double zd = c;
    if (zmode == "elevation") zd = top - c;
    if (zmode == "depth") {
      const Coord column{
          uint32_t(std::clamp((x - u.origin_m[0]) / u.tick_m, 0.0, double(kRootEdge))),
          uint32_t(std::clamp((y - u.origin_m[1]) / u.tick_m, 0.0, double(kRootEdge))), 0};
      zd = top - ex.ground_at(column) + c;
    }
    char buf[128];
    std::snprintf(buf, sizeof buf, "%.17g %.17g %.17g", x, y, zd);
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
  PointBatchOptions o{q, s.mode, s.metres, false, {}};
  o.helpers = s.helpers;
  o.batch_points = s.batch_points;
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
  if (!h.inside && ex.in_air(c)) {
    std::fprintf(out, "point (%s) is in the air, above the ground (elevation %.6g m there)\n",
                 asked.c_str(), ex.ground_at(c));
    return 0;
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

}  // namespace weaver::cli
