#include <chrono>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "cli/cli.h"
#include "modeldb/db_model.h"
#include "modeldb/model_import.h"

namespace weaver::cli {
namespace {

constexpr char kUsage[] =
    "usage: weaver model import MODEL.db --from etree:FILE|grid:FILE|layers:FILE|xyz:FILE\n"
    "                           [--tolerance REL] [--root-edge METRES] [--memory BYTES]\n"
    "                           [--plain]\n"
    "       weaver model material MODEL.db X Y Z | --points FILE [--memory BYTES]\n"
    "\n"
    "A velocity model as a database of its own: an octree of materials (Vp, Vs,\n"
    "density, and Qp, Qs where the source has them) keyed like weaver's octants,\n"
    "which 'weaver construct DB --model db:MODEL.db' samples.\n"
    "\n"
    "import: reads the model and writes MODEL.db's model table by sorted append,\n"
    "merging eight children into their parent where every value agrees within\n"
    "the tolerance; the database is left as it was on any error.\n"
    "  --from etree:FILE  a file of the original etree library (SCEC CVM etrees,\n"
    "                     UCVM's ucvm2etree, the USGS Bay Area model): its leaves,\n"
    "                     fields found by name in its schema; size and origin from\n"
    "                     its metadata\n"
    "  --from grid:FILE   a weaver-grid 1 file (src/model/grid_model.h), read a\n"
    "                     block of rows at a time: one octant per grid point\n"
    "  --from layers:FILE a 1-D layered model, one line a layer: 'top_depth vp vs\n"
    "                     rho [qp qs]' (metres, m/s, kg/m^3; the first top 0, tops\n"
    "                     increasing, the last layer a half-space; '#' comments)\n"
    "  --from xyz:FILE    a regular grid as ASCII 'x y z vp vs rho' lines in any\n"
    "                     order (SPECFEM3D tomography style), every point once;\n"
    "                     placed on disk in grid order first, never held whole\n"
    "  --tolerance REL    merge siblings whose values differ by at most REL of the\n"
    "                     smallest (default 0: exactly equal)\n"
    "  --root-edge M      etree: the edge of the etree's root in metres, when its\n"
    "                     metadata does not say\n"
    "  --memory BYTES     memory budget (default 256M): the table's cache\n"
    "  --plain            plain leaf pages (default: packed)\n"
    "\n"
    "material: the model's values at X Y Z (metres in the model's frame, z depth\n"
    "down), one line 'x y z vp vs rho [qp qs]' a point; --points FILE reads\n"
    "'x y z' lines ('#' comments and blank lines skipped).  Points outside the\n"
    "model's box take the value of the nearest model cell.\n";

Status print_material(const DbModel& m, double x, double y, double z) {
  ModelHit h;
  WEAVER_RETURN_IF_ERROR(m.lookup(x, y, z, &h));
  std::printf("%.10g %.10g %.10g %.9g %.9g %.9g", x, y, z, h.values[0], h.values[1], h.values[2]);
  if (m.info().has_q) std::printf(" %.9g %.9g", h.values[3], h.values[4]);
  std::printf("\n");
  return Status::Ok();
}

int material(const ParsedArgs& args) {
  const auto& pos = args.positional;  // "material" DB [X Y Z]
  const bool batch = args.values.count("points") != 0;
  if (pos.size() != (batch ? 2u : 5u)) {
    return usage_error("model", "expected MODEL.db and X Y Z, or --points FILE", kUsage);
  }
  MemoryBudget memory;
  Status st = memory_option(args, &memory);
  if (!st.ok()) return usage_error("model", st.message(), kUsage);
  std::unique_ptr<DbModel> m;
  st = DbModel::open(pos[1], memory, 1, &m);
  if (!st.ok()) return report("model", st);
  if (!batch) {
    double p[3];
    for (int a = 0; a < 3; ++a) {
      st = parse_double(pos[2 + a], "coordinate", &p[a]);
      if (!st.ok()) return usage_error("model", st.message(), kUsage);
    }
    st = print_material(*m, p[0], p[1], p[2]);
    return st.ok() ? 0 : report("model", st);
  }
  std::ifstream in(args.values.at("points"));
  if (!in) return report("model", Status::NotFound(args.values.at("points") + ": cannot open"));
  std::string line;
  for (uint64_t n = 1; std::getline(in, line); ++n) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream s(line);
    double x, y, z;
    if (!(s >> x >> y >> z)) {
      return report("model", Status::Corruption(args.values.at("points") + ": line " +
                                                std::to_string(n) + " is not 'x y z'"));
    }
    st = print_material(*m, x, y, z);
    if (!st.ok()) return report("model", st);
  }
  return 0;
}

int import(const ParsedArgs& args) {
  if (args.positional.size() != 2) return usage_error("model", "expected one MODEL.db", kUsage);
  if (!args.values.count("from")) return usage_error("model", "--from is required", kUsage);
  ModelImportOptions o;
  o.from = args.values.at("from");
  o.packed = !args.flags.count("plain");
  Status st = memory_option(args, &o.memory);
  if (st.ok() && args.values.count("tolerance"))
    st = parse_double(args.values.at("tolerance"), "--tolerance", &o.tolerance);
  if (st.ok() && args.values.count("root-edge"))
    st = parse_double(args.values.at("root-edge"), "--root-edge", &o.root_edge_m);
  if (!st.ok()) return usage_error("model", st.message(), kUsage);
  const auto t0 = std::chrono::steady_clock::now();
  ModelImportResult r;
  st = import_model(args.positional[1], o, &r);
  if (!st.ok()) return report("model", st);
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const ModelInfo& i = r.info;
  std::printf("source     %s\n", i.source.c_str());
  std::printf("read       %llu %s in %.2f s (%.3gM/s)\n", (unsigned long long)r.read,
              o.from.rfind("etree:", 0) == 0    ? "leaves"
              : o.from.rfind("layers:", 0) == 0 ? "layers"
                                                : "grid points",
              s, r.read / s / 1e6);
  std::printf("stored     %llu octants (%.1f%% of those read), %.3g MB, levels",
              (unsigned long long)r.octants, 100.0 * r.octants / std::max<uint64_t>(r.read, 1),
              r.table_bytes / 1e6);
  for (int l = 0; l <= kMaxLevel; ++l) {
    if (r.levels[l]) std::printf(" %d:%llu", l, (unsigned long long)r.levels[l]);
  }
  if (i.extent_m[0] == 0 && i.extent_m[1] == 0) {
    std::printf("\nbox        any x, y; depth %g m from %g (deeper: the last layer)%s\n",
                i.extent_m[2], i.origin_m[2], i.has_q ? "; with Qp, Qs" : "");
  } else {
    std::printf("\nbox        %g x %g x %g m from (%g, %g, %g)%s\n", i.extent_m[0], i.extent_m[1],
                i.extent_m[2], i.origin_m[0], i.origin_m[1], i.origin_m[2],
                i.has_q ? "; with Qp, Qs" : "");
  }
  if (!i.geo.empty()) std::printf("geo        origin lon,lat[,azimuth] %s\n", i.geo.c_str());
  if (!i.producer.empty()) std::printf("producer   %s\n", i.producer.c_str());
  return 0;
}

}  // namespace

int cmd_model(int argc, char** argv) {
  ParsedArgs args;
  Status st = parse_args(argc, argv, 2, {"from", "tolerance", "root-edge", "memory", "points"},
                         {"plain"}, &args);
  if (args.help) return std::fputs(kUsage, stdout), 0;
  if (!st.ok()) return usage_error("model", st.message(), kUsage);
  const std::string sub = args.positional.empty() ? "" : args.positional[0];
  if (sub == "import") return import(args);
  if (sub == "material") return material(args);
  return usage_error("model", "expected 'import' or 'material'", kUsage);
}

}  // namespace weaver::cli
