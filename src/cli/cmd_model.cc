#include <chrono>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <vector>

#include "cli/cli.h"
#include "modeldb/db_model.h"
#include "modeldb/model_import.h"
#include "util/progress.h"

namespace weaver::cli {
namespace {

constexpr char kUsage[] =
    "usage: weaver model import MODEL.db --from "
    "etree:FILE|grid:FILE|layers:FILE|xyz:FILE|rfile:FILE\n"
    "                           [--tolerance REL] [--root-edge METRES] [--memory BYTES]\n"
    "                           [--threads N] [--plain] [--quiet]\n"
    "       weaver model material MODEL.db X Y Z | --points FILE [--outside clamp|error]\n"
    "                             [--memory BYTES]\n"
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
    "  --from rfile:FILE  an SW4 rfile (docs/ground.md): each block's cells, as fine\n"
    "                     as its smaller spacing (to a power of two of the tick),\n"
    "                     valued as SW4 samples the file at their centres; z is\n"
    "                     metres down from sea level ('mesh --model rfile:FILE'\n"
    "                     samples the file itself)\n"
    "  --tolerance REL    merge siblings whose values differ by at most REL of the\n"
    "                     smallest (default 0: exactly equal)\n"
    "  --root-edge M      etree: the edge of the etree's root in metres, when its\n"
    "                     metadata does not say\n"
    "  --memory BYTES     memory budget (default 256M): the table's cache\n"
    "  --threads N        rfile: threads that sample the file, a subtree each,\n"
    "                     written in key order (default: the number of cores);\n"
    "                     the same table for every N\n"
    "  --plain            plain leaf pages (default: packed)\n"
    "  --quiet            no progress line on stderr (default: one that updates\n"
    "                     itself on a terminal, a line every 10 s otherwise: the\n"
    "                     octants stored so far)\n"
    "\n"
    "material: the model's values at X Y Z (metres in the model's frame, z depth\n"
    "down), one line 'x y z vp vs rho [qp qs]' a point; --points FILE reads\n"
    "'x y z' lines ('#' comments and blank lines skipped), answered a batch at a\n"
    "time in Z-order (any order of the file is as fast as a sorted one).\n"
    "  --outside clamp    a point outside the model's box takes the values of the\n"
    "                     nearest model cell, and a note on stderr counts them\n"
    "                     (the default)\n"
    "  --outside error    such a point fails the command, naming it\n";

std::string describe_point(const double* p) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "(%g, %g, %g) m", p[0], p[1], p[2]);
  return buf;
}

void print_material(const DbModel& m, const double* p, const ModelHit& h) {
  std::printf("%.10g %.10g %.10g %.9g %.9g %.9g", p[0], p[1], p[2], h.values[0], h.values[1],
              h.values[2]);
  if (m.info().has_q) std::printf(" %.9g %.9g", h.values[3], h.values[4]);
  std::printf("\n");
}

// Answers the points (x, y, z each) and prints them in their order; counts
// those outside the model's box into *outside, or fails on the first when
// they are errors.
Status answer(const DbModel& m, const std::vector<double>& xyz, bool outside_error,
              std::vector<ModelHit>* hits, uint64_t* outside, std::string* first) {
  const size_t n = xyz.size() / 3;
  hits->resize(n);
  WEAVER_RETURN_IF_ERROR(m.lookup_batch(xyz.data(), n, hits->data()));
  for (size_t i = 0; i < n; ++i) {
    if ((*hits)[i].clamped) {
      if (outside_error) return m.outside_box(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
      if ((*outside)++ == 0) *first = describe_point(&xyz[3 * i]);
    }
  }
  for (size_t i = 0; i < n; ++i) print_material(m, &xyz[3 * i], (*hits)[i]);
  return Status::Ok();
}

// Reads 'x y z' lines into batches and answers each.
Status answer_file(const DbModel& m, const std::string& path, bool outside_error, uint64_t* outside,
                   std::string* first) {
  constexpr size_t kBatch = size_t{1} << 18;  // points: 10 MB of them and their answers
  std::ifstream in(path);
  if (!in) return Status::NotFound(path + ": cannot open");
  std::vector<double> xyz;
  std::vector<ModelHit> hits;
  std::string line;
  for (uint64_t n = 1; std::getline(in, line); ++n) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream s(line);
    double p[3];
    if (!(s >> p[0] >> p[1] >> p[2])) {
      return Status::Corruption(path + ": line " + std::to_string(n) + " is not 'x y z'");
    }
    xyz.insert(xyz.end(), p, p + 3);
    if (xyz.size() == 3 * kBatch) {
      WEAVER_RETURN_IF_ERROR(answer(m, xyz, outside_error, &hits, outside, first));
      xyz.clear();
    }
  }
  return answer(m, xyz, outside_error, &hits, outside, first);
}

int material(const ParsedArgs& args) {
  const auto& pos = args.positional;  // "material" DB [X Y Z]
  const bool batch = args.values.count("points") != 0;
  if (pos.size() != (batch ? 2u : 5u)) {
    return usage_error("model", "expected MODEL.db and X Y Z, or --points FILE", kUsage);
  }
  MemoryBudget memory;
  Status st = memory_option(args, &memory);
  bool outside_error = false;
  if (st.ok()) st = outside_option(args, &outside_error);
  std::vector<double> xyz;
  for (size_t a = 2; st.ok() && !batch && a < 5; ++a) {
    xyz.push_back(0);
    st = parse_double(pos[a], "coordinate", &xyz.back());
  }
  if (!st.ok()) return usage_error("model", st.message(), kUsage);
  std::unique_ptr<DbModel> m;
  st = DbModel::open(pos[1], memory, 1, &m);
  uint64_t outside = 0;
  std::string first;
  std::vector<ModelHit> hits;
  if (st.ok()) {
    st = batch ? answer_file(*m, args.values.at("points"), outside_error, &outside, &first)
               : answer(*m, xyz, outside_error, &hits, &outside, &first);
  }
  if (!st.ok()) return report("model", st);
  if (outside > 0) {
    std::fprintf(stderr,
                 "weaver model: note: %llu point(s) outside the model's box took the nearest "
                 "model cell's values (first: %s; --outside error refuses them)\n",
                 (unsigned long long)outside, first.c_str());
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
  if (st.ok()) st = threads_option(args, default_threads(), &o.threads);
  if (st.ok()) st = check_target_kind(args.positional[1], false);
  if (!st.ok()) return usage_error("model", st.message(), kUsage);
  const auto t0 = std::chrono::steady_clock::now();
  ModelImportResult r;
  {
    ProgressLine line(ProgressLine::style_for_stderr(args.flags.count("quiet")), "model import",
                      "octants");
    o.progress = line.fn();
    st = import_model(args.positional[1], o, &r);
  }
  if (!st.ok()) return report("model", st);
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const ModelInfo& i = r.info;
  std::printf("source     %s\n", i.source.c_str());
  std::printf("read       %llu %s in %.2f s (%.3gM/s)\n", (unsigned long long)r.read,
              o.from.rfind("etree:", 0) == 0    ? "leaves"
              : o.from.rfind("layers:", 0) == 0 ? "layers"
              : o.from.rfind("rfile:", 0) == 0  ? "cells sampled"  // not the file's points
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
  Status st = parse_args(
      argc, argv, 2, {"from", "tolerance", "root-edge", "memory", "points", "outside", "threads"},
      {"plain", "quiet"}, &args);
  if (args.help) return std::fputs(kUsage, stdout), 0;
  if (!st.ok()) return usage_error("model", st.message(), kUsage);
  const std::string sub = args.positional.empty() ? "" : args.positional[0];
  if (sub == "import") return import(args);
  if (sub == "material") return material(args);
  return usage_error("model", "expected 'import' or 'material'", kUsage);
}

}  // namespace weaver::cli
