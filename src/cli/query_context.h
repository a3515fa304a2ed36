// One query of `weaver query` or the shell, as it runs: its words parsed,
// the settings it inherits, where its answers and errors go, and the cells
// every answer is made of.  The queries themselves are in
// query_points.cc (locate, material, node-at), query_ids.cc (range,
// element, node) and query_neighbourhoods.cc (neighbors, node-elements,
// depends); query_commands.cc parses and dispatches them.
#pragma once

#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "cli/point_batch.h"
#include "cli/query_commands.h"
#include "util/args.h"

namespace weaver::cli {

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
  // Points given as --geo's LON LAT DEPTH and/or with --z elevation|depth,
  // into the frame's metres (z down from the domain's top).
  Status to_frame_metres(bool geo, const std::string& z);
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

// "x y z" of a tick point.
inline std::string point_text(Coord c) {
  return std::to_string(c.x) + " " + std::to_string(c.y) + " " + std::to_string(c.z);
}

}  // namespace weaver::cli
