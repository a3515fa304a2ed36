#include <algorithm>
#include <chrono>
#include <cstdio>
#include <vector>

#include "cli/cli.h"
#include "db/output_path.h"
#include "export/export.h"
#include "util/printable.h"
#include "util/progress.h"

namespace weaver::cli {
namespace {

constexpr char kUsage[] =
    "usage: weaver export DB --format FORMAT --out PATH [--units m|ticks] [--z-up]\n"
    "                        [--box X0,Y0,Z0,X1,Y1,Z1] [--parts N] [--memory BYTES] [--quiet]\n"
    "       weaver export DB [--nodes FILE] [--elements FILE]     (csv, as --format csv)\n"
    "\n"
    "Writes the extracted mesh of DB for the tools of the field, streaming, in id\n"
    "order.  Every file is written beside PATH and renamed into place when complete.\n"
    "  --format vtu         VTK XML UnstructuredGrid (ParaView, VisIt, pyvista):\n"
    "                       hexahedra in VTK's corner order; cell data element_id,\n"
    "                       level, edge, vp, vs, rho; point data node_id, kind\n"
    "                       (0 anchored, 1 edge-dangling, 2 face-dangling)\n"
    "  --format pvtu        the vtu in --parts N pieces: PATH (name.pvtu, the index\n"
    "                       ParaView opens) and the pieces in the directory name/\n"
    "  --format msh         Gmsh MSH 4.1 (ASCII): hexahedra, element data level\n"
    "                       (and vp, vs, rho); tags are ids + 1\n"
    "  --format metis       the element dual graph for gpmetis: elements sharing a\n"
    "                       face, the 4 finer ones across a 2:1 step included\n"
    "  --format metis-mesh  the elements as an mpmetis mesh file (its own dual graph\n"
    "                       misses the 2:1 faces: prefer metis)\n"
    "  --format raw         a directory PATH with mesh.bin (little-endian arrays) and\n"
    "                       mesh.json (each array's dtype, shape, offset) for numpy\n"
    "                       and solvers: coordinates, kinds, corners, levels,\n"
    "                       material, dangling nodes and their anchors\n"
    "  --format csv         PATH/nodes.csv and PATH/elements.csv:\n"
    "  --nodes FILE         id,x,y,z,kind,a0,a1,a2,a3  (kind anchored|edge|face; anchors\n"
    "                       are node ids, ascending, empty where fewer than 4)\n"
    "  --elements FILE      id,x,y,z,level,n0,...,n7   (node ids of corners 0..7, x fastest)\n"
    "                       csv coordinates are in ticks\n"
    "  --units m|ticks      coordinates of vtu, msh, raw and --box (default m: origin +\n"
    "                       tick size times ticks, as the octant table's metadata says)\n"
    "  --z-up               z as elevation, metres up (the top's elevation minus\n"
    "                       the depth; raw's mesh.json says z_up), so that ParaView\n"
    "                       shows the ground's mountains upright\n"
    "  --box X0,Y0,Z0,X1,Y1,Z1  vtu, pvtu, msh, raw: only the elements sharing a point\n"
    "                       with the box, and the nodes they use (raw: and their\n"
    "                       anchors), renumbered compactly; node_id / element_id\n"
    "                       (raw: node_global_id / element_global_id) keep global ids\n"
    "  --parts N            pvtu: N pieces; raw: PATH/part-00000/ ... one raw export a\n"
    "                       part (local numbering, global ids, its dangling constraints,\n"
    "                       shared_nodes/shared_parts) and PATH/parts.json.  The parts\n"
    "                       of the stored partition ('weaver partition') when it has\n"
    "                       N parts, else N ranges of element ids of equal count\n"
    "  --memory BYTES       memory budget (default 256M): the node table's cache (half),\n"
    "                       the octant table's (an eighth, at most 16M), the output\n"
    "                       buffers (an eighth, at most 12M) and, for --box and\n"
    "                       --parts, the sort and tree of their node set (an eighth)\n"
    "  --quiet              no progress line on stderr (default: items written of all,\n"
    "                       updated on a terminal, every 10 s otherwise)\n";

}  // namespace

Status parse_export_options(const ParsedArgs& args, ExportOptions* o) {
  auto values = args.values;
  Status st;
  o->nodes_path = values.count("nodes") ? values["nodes"] : "";
  o->elements_path = values.count("elements") ? values["elements"] : "";
  o->out = values.count("out") ? values["out"] : "";
  const bool csv_files = !o->nodes_path.empty() || !o->elements_path.empty();
  if (values.count("format")) {
    if (!export_format_from_name(values["format"], &o->format)) {
      return Status::InvalidArgument("unknown --format '" + values["format"] + "'");
    }
  } else if (!csv_files) {
    return Status::InvalidArgument("give --format FORMAT --out PATH (or --nodes/--elements)");
  }
  if (csv_files && (o->format != ExportFormat::kCsv || !o->out.empty())) {
    return Status::InvalidArgument("--nodes/--elements are csv files: not with --out");
  }
  if (!csv_files && o->out.empty()) return Status::InvalidArgument("--out PATH is missing");
  if (values.count("units")) {
    const std::string& u = values["units"];
    if (u != "m" && u != "ticks") {
      return Status::InvalidArgument("--units is m or ticks, not '" + u + "'");
    }
    o->units = u == "m" ? ExportUnits::kMetres : ExportUnits::kTicks;
  }
  o->z_up = args.flags.count("z-up") != 0;
  if (o->z_up && o->units == ExportUnits::kTicks)
    return Status::InvalidArgument("--z-up writes metres: not with --units ticks");
  if (values.count("box")) {
    std::vector<double> box;
    st = parse_double_list(values["box"], "--box", 6, &box);
    if (!st.ok()) return st;
    std::copy(box.begin(), box.end(), o->box);
    o->has_box = true;
  }
  if (values.count("parts")) {
    uint64_t parts = 0;
    st = parse_count(values["parts"], "--parts", &parts);
    if (st.ok() && (parts < 1 || parts > 100000)) {
      st = Status::InvalidArgument("--parts must be 1 to 100000");
    }
    if (!st.ok()) return st;
    o->parts = uint32_t(parts);
  }
  const ExportFormat f = o->format;
  if (o->has_box && f != ExportFormat::kVtu && f != ExportFormat::kPvtu &&
      f != ExportFormat::kMsh && f != ExportFormat::kRaw) {
    return Status::InvalidArgument("--box works with vtu, pvtu, msh and raw");
  }
  if (o->parts > 1 && f != ExportFormat::kPvtu && f != ExportFormat::kRaw) {
    return Status::InvalidArgument("--parts works with pvtu and raw");
  }
  if (o->parts > 1 && o->has_box && f == ExportFormat::kRaw) {
    return Status::InvalidArgument("raw takes --box or --parts, not both");
  }
  // Nothing written into a database, whatever the path says.
  for (const std::string& path : {o->out, o->nodes_path, o->elements_path,
                                  f == ExportFormat::kPvtu ? pvtu_stem(o->out) : ""}) {
    if (!path.empty()) WEAVER_RETURN_IF_ERROR(check_output_path(path));
  }
  return memory_option(args, &o->memory);
}

int cmd_export(int argc, char** argv) {
  ParsedArgs args;
  Status st = parse_args(argc, argv, 2,
                         {"nodes", "elements", "memory", "format", "out", "units", "box", "parts"},
                         {"quiet", "z-up"}, &args);
  if (args.help) return std::fputs(kUsage, stdout), 0;
  if (!st.ok()) return usage_error("export", st.message(), kUsage);
  if (args.positional.size() != 1) return usage_error("export", "expected one DB", kUsage);
  ExportOptions o;
  st = parse_export_options(args, &o);
  if (!st.ok()) return usage_error("export", st.message(), kUsage);
  const auto t0 = std::chrono::steady_clock::now();
  ExportResult r;
  ProgressLine line(ProgressLine::style_for_stderr(args.flags.count("quiet")), "export", "items");
  o.progress = line.fn();
  st = export_mesh(args.positional[0], o, &r);
  line.finish();
  if (!st.ok()) return report("export", st);
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("exported %llu nodes and %llu elements", (unsigned long long)r.nodes,
              (unsigned long long)r.elements);
  if (o.format == ExportFormat::kMetis) {
    std::printf(" (%llu graph edges)", (unsigned long long)r.graph_edges);
  }
  std::printf(" in %.2fs, %sB written\n", secs, si_text(double(r.bytes)).c_str());
  return 0;
}

}  // namespace weaver::cli
