#include <chrono>
#include <cstdio>

#include "cli/cli.h"
#include "export/export_csv.h"
#include "util/progress.h"

namespace weaver::cli {
namespace {

constexpr char kUsage[] =
    "usage: weaver export DB [--nodes FILE] [--elements FILE] [--memory BYTES] [--quiet]\n"
    "\n"
    "Writes the extracted mesh of DB as CSV, rows in id order, streaming:\n"
    "  --nodes FILE     id,x,y,z,kind,a0,a1,a2,a3  (kind anchored|edge|face; anchors\n"
    "                   are node ids, ascending, empty where fewer than 4)\n"
    "  --elements FILE  id,x,y,z,level,n0,...,n7   (node ids of corners 0..7, x fastest)\n"
    "Coordinates are in ticks.  Each file is renamed into place when complete.\n"
    "  --memory BYTES   memory budget (default 256M): the node table's cache (half)\n"
    "                   and the octant table's (an eighth, at most 4M)\n"
    "  --quiet          no progress line on stderr (default: rows written of all\n"
    "                   rows, updated on a terminal, every 10 s otherwise)\n";

}  // namespace

int cmd_export(int argc, char** argv) {
  ParsedArgs args;
  Status st = parse_args(argc, argv, 2, {"nodes", "elements", "memory"}, {"quiet"}, &args);
  if (args.help) return std::fputs(kUsage, stdout), 0;
  if (!st.ok()) return usage_error("export", st.message(), kUsage);
  if (args.positional.size() != 1) return usage_error("export", "expected one DB", kUsage);
  ExportOptions o;
  o.nodes_path = args.values.count("nodes") ? args.values["nodes"] : "";
  o.elements_path = args.values.count("elements") ? args.values["elements"] : "";
  if (o.nodes_path.empty() && o.elements_path.empty()) {
    return usage_error("export", "give --nodes FILE and/or --elements FILE", kUsage);
  }
  st = memory_option(args, &o.memory);
  if (!st.ok()) return usage_error("export", st.message(), kUsage);
  const auto t0 = std::chrono::steady_clock::now();
  ExportResult r;
  ProgressLine line(ProgressLine::style_for_stderr(args.flags.count("quiet")), "export", "rows");
  o.progress = line.fn();
  st = export_csv(args.positional[0], o, &r);
  line.finish();
  if (!st.ok()) return report("export", st);
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("exported %llu nodes and %llu elements in %.2fs\n", (unsigned long long)r.nodes,
              (unsigned long long)r.elements, secs);
  return 0;
}

}  // namespace weaver::cli
