#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

#include "balance/balance.h"
#include "cli/cli.h"
#include "construct/construct.h"
#include "construct/estimate.h"
#include "db/database.h"
#include "extract/extract.h"
#include "modeldb/open_model.h"
#include "schema/octant.h"
#include "util/progress.h"

namespace weaver::cli {
namespace {

constexpr char kUsage[] =
    "usage: weaver mesh DB --model NAME --freq F [--ppw N] [--vs-min V] [--domain LX,LY,LZ]\n"
    "                      [--min-level L] [--max-level L] [--grid FILE] [--threads N]\n"
    "                      [--max-elements N] [--memory BYTES] [--origin-geo LON,LAT\n"
    "                      [--azimuth DEG] [--utm-zone Z]] [--outside clamp|error]\n"
    "                      [--surface SOURCE [--surface-crs frame|lonlat]]\n"
    "                      [--top-elevation E] [--model-z depth|elevation]\n"
    "                      [--surface-edge M] [--plain] [--unbalanced] [--quiet]\n"
    "\n"
    "The whole pipeline: construct the octree from the model, 2:1 balanced as it is\n"
    "descended, and extract the mesh (--unbalanced: construct, then 'weaver balance',\n"
    "then extract, as before).  Prints a line per stage (count, rate, time, peak memory), then "
    "the\n"
    "mesh summary (elements, nodes, dangling nodes, as in the paper's Figure 11) and\n"
    "its quality: elements per level, smallest and largest edge, and the fewest\n"
    "points per wavelength at any element.  Options as for 'weaver construct';\n"
    "--threads N is for the stages that use threads (default: the number of cores;\n"
    "the tables are the same for every N); --quiet drops the progress\n"
    "lines (see each stage's --help for what their percent means);\n"
    "--plain writes plain leaf pages in every table (default: packed).  If a\n"
    "stage fails, the error says which stages had committed their tables.  Last, the\n"
    "boundary table ('weaver boundary --help'), timed apart.\n"
    "--memory (default 256M) bounds each stage in turn, as in that stage's command.\n"
    "\n" WEAVER_GROUND_USAGE;

// Peak resident memory since the last reset_peak(), from the kernel's high
// water mark (Linux); 0 where unavailable.
uint64_t peak_rss() {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("VmHWM:", 0) == 0) return std::stoull(line.substr(6)) * 1024;
  }
  return 0;
}
void reset_peak() { std::ofstream("/proc/self/clear_refs") << "5"; }

// The bytes this process has read and written through read/write calls
// (rchar, wchar of /proc/self/io: page cache hits included, so what the
// stages ask of the disk, not what reaches it); 0 where unavailable.
struct IoBytes {
  uint64_t read = 0, written = 0;
  static IoBytes now() {
    IoBytes b;
    std::ifstream in("/proc/self/io");
    std::string key;
    uint64_t value = 0;
    while (in >> key >> value) {
      if (key == "rchar:") b.read = value;
      if (key == "wchar:") b.written = value;
    }
    return b;
  }
};

struct Stage {
  std::chrono::steady_clock::time_point t0 = std::chrono::steady_clock::now();
  IoBytes io0 = IoBytes::now();
  double seconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  // Bytes read and written since the stage began.
  IoBytes io() const {
    const IoBytes b = IoBytes::now();
    return {b.read - io0.read, b.written - io0.written};
  }
};

void stage_line(const char* name, uint64_t count, const char* what, const Stage& s) {
  const double secs = s.seconds();
  const IoBytes io = s.io();
  std::printf("%-10s %12llu %-9s %7.2fs %12.0f/s  peak %6.1f MB  read %8.1f MB  wrote %8.1f MB\n",
              name, (unsigned long long)count, what, secs, count / secs, peak_rss() / 1e6,
              io.read / 1e6, io.written / 1e6);
  std::fflush(stdout);
}

// The bytes of the files in a database directory.
uint64_t directory_bytes(const std::string& dir) {
  uint64_t n = 0;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(dir, ec)) {
    if (e.is_regular_file(ec)) n += e.file_size(ec);
  }
  return n;
}

// A later stage failed: say so, and what the earlier ones left committed.
int report_after(const char* stage, const Status& st, const char* committed) {
  std::fprintf(stderr, "weaver mesh: %s failed: %s (%s)\n", stage, error_text(st).c_str(),
               committed);
  return 1;
}

}  // namespace

int cmd_mesh(int argc, char** argv) {
  ParsedArgs args;
  Status st = parse_args(
      argc, argv, 2, {"model",        "grid",        "freq",          "ppw",      "vs-min",
                      "domain",       "min-level",   "max-level",     "memory",   "threads",
                      "max-elements", "origin-geo",  "azimuth",       "utm-zone", "outside",
                      "surface",      "surface-crs", "top-elevation", "model-z",  "surface-edge"},
      {"plain", "quiet", "unbalanced"}, &args);
  if (args.help) return std::fputs(kUsage, stdout), 0;
  if (!st.ok()) return usage_error("mesh", st.message(), kUsage);
  if (args.positional.size() != 1) return usage_error("mesh", "expected one DB", kUsage);
  if (!args.values.count("freq")) return usage_error("mesh", "--freq F is required", kUsage);
  ConstructOptions co;
  co.whole_pipeline = true;
  st = parse_construct_options(args, &co);
  ExtractOptions eo;
  if (st.ok()) {
    st = threads_option(args, default_threads(), &eo.threads);
  }
  // A model database given as the mesh's target (a model source file is
  // imported into the target, which then holds both).
  if (st.ok() && !is_model_source(co.model)) st = check_target_kind(args.positional[0], true);
  if (!st.ok()) return usage_error("mesh", st.message(), kUsage);
  eo.memory = co.memory;
  co.threads = eo.threads;
  eo.packed = co.packed;
  const std::string& db = args.positional[0];
  st = import_model_option(db, &co);
  if (!st.ok()) return report("mesh", st);
  ConstructPlan plan;
  st = plan_construct(co, &plan);
  if (st.is_invalid_argument()) return usage_error("mesh", st.message(), kUsage);
  if (!st.ok()) return report("mesh", st);
  print_construct_plan(co, plan, db);
  // One pass commits once: construct stages the octant table in this
  // writer, and extract's commit makes it live with the node table, so a
  // re-mesh leaves the old mesh or the new one (Database::stage).
  std::unique_ptr<Database> writer;
  if (co.balanced) {
    // Refuse a runaway size before the writer creates DB.
    st = check_construct_fits(co, planned_estimate(plan), db);
    if (st.ok()) st = Database::open(db, Database::Mode::kWrite, true, &writer);
    if (!st.ok()) return report("mesh", st);
    co.writer = eo.writer = writer.get();
    // Construct and extract stage their tables; the boundary's commit
    // makes all three live at once.
    co.stage = eo.stage = true;
  }
  const Stage total;

  reset_peak();
  Stage s1;
  ConstructResult cr;
  const ProgressLine::Style style = ProgressLine::style_for_stderr(args.flags.count("quiet"));
  ProgressLine construct_line(style, "construct", "leaves");
  co.progress = construct_line.fn();
  st = construct_octree(db, co, &plan, &cr);
  construct_line.finish();
  if (!st.ok()) return report("mesh", st);
  stage_line("construct", cr.elements, "leaves", s1);
  print_construct_balance(cr);

  LevelCounts levels = cr.levels;
  if (!co.balanced) {
    reset_peak();
    Stage s2;
    BalanceOptions bo;
    bo.memory = co.memory;
    bo.threads = eo.threads;
    if (names_model_database(co.model)) bo.model_dirs.push_back(model_database_dir(co.model));
    ProgressLine balance_line(style, "balance", "leaves");
    bo.progress = balance_line.fn();
    BalanceResult br;
    st = balance_octree(db, bo, &br);
    balance_line.finish();
    if (!st.ok()) return report_after("balance", st, "construct committed the octant table");
    stage_line("balance", br.output_leaves, "leaves", s2);
    levels = br.levels;
  }

  reset_peak();
  Stage s3;
  ProgressLine extract_line(style, "extract", "elements");
  eo.progress = extract_line.fn();
  ExtractResult er;
  st = extract_mesh(db, eo, &er);
  extract_line.finish();
  if (!st.ok()) {
    return report_after("extract", st,
                        co.balanced ? "nothing committed: the database is as it was"
                                    : "construct and balance committed the balanced octant table");
  }
  stage_line("extract", er.nodes, "nodes", s3);

  // The boundary faces (timed apart: the stages before are the paper's
  // pipeline), committed with the mesh's tables.
  reset_peak();
  Stage s4;
  BoundaryOptions bo;
  bo.memory = co.memory;
  bo.packed = co.packed;
  bo.threads = eo.threads;
  bo.writer = writer.get();
  // Construct found the least edge / vp of the leaves it wrote; a balance
  // after it (--unbalanced) splits some, so then the boundary's scan finds it.
  if (co.balanced && cr.least_dt < HUGE_VAL) {
    bo.known_least_dt = cr.least_dt;
    bo.known_least_dt_element = cr.least_dt_element;
  }
  // Where construct cut no air its leaves fill its blocks; else it found
  // the box they span as it wrote them (a balance after it splits leaves,
  // which changes neither): the box is known.
  if (!plan.carved) {
    const uint32_t block = uint32_t{1} << (kMaxLevel - plan.block_level);
    bo.known_box = true;
    for (int a = 0; a < 3; ++a) bo.box_hi[a] = plan.blocks[a] * block;
  } else if (cr.elements > 0) {
    LeafSpan span = cr.span;
    span.settle();
    bo.known_box = true;
    bo.box_filled = span.filled;
    bo.box_lo = span.lo, bo.box_hi = span.hi;
  }
  ProgressLine boundary_line(style, "boundary", "elements");
  bo.progress = boundary_line.fn();
  BoundaryResult br;
  st = build_boundary(db, bo, &br);
  boundary_line.finish();
  if (!st.ok()) {
    return report_after("boundary", st,
                        co.balanced ? "nothing committed: the database is as it was"
                                    : "the mesh is committed, its boundary table not");
  }
  stage_line("boundary", br.faces, "faces", s4);

  std::printf("\nmesh at %g Hz, %g points per wavelength, in %.2fs\n", co.freq, co.ppw,
              total.seconds());
  const uint64_t db_bytes = directory_bytes(db);
  const IoBytes io = total.io();
  std::printf("  database   %.1f MB; the run wrote %.1f MB (%.2fx) and read %.1f MB\n",
              db_bytes / 1e6, io.written / 1e6,
              double(io.written) / std::max<uint64_t>(1, db_bytes), io.read / 1e6);
  std::printf(
      "  elements   %llu\n  nodes      %llu\n  danglings  %llu (%llu on edges, %llu on "
      "faces)\n",
      (unsigned long long)er.elements, (unsigned long long)er.nodes,
      (unsigned long long)(er.edge + er.face), (unsigned long long)er.edge,
      (unsigned long long)er.face);
  int finest = 0, coarsest = kMaxLevel;
  std::printf("  elements per level (edge):\n");
  for (int l = 0; l <= kMaxLevel; ++l) {
    if (levels[l] == 0) continue;
    finest = std::max(finest, l);
    coarsest = std::min(coarsest, l);
    std::printf("    level %2d (%9.2f m)  %llu\n", l, plan.root_edge_m / (1 << l),
                (unsigned long long)levels[l]);
  }
  std::printf("  edges %.2f m .. %.2f m; at least %.2f points per wavelength everywhere\n",
              plan.root_edge_m / (1 << finest), plan.root_edge_m / (1 << coarsest), cr.worst_ppw);
  print_boundary(br, s4.seconds());

  return 0;
}

}  // namespace weaver::cli
