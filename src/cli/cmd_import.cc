#include <unistd.h>

#include <chrono>
#include <cstdio>

#include "cli/cli.h"
#include "import/import.h"
#include "util/progress.h"

namespace weaver::cli {
namespace {

constexpr char kUsage[] =
    "usage: weaver import DB --octants FILE [--memory BYTES] [--tick METRES]\n"
    "                        [--origin X,Y,Z] [--plain] [--quiet]\n"
    "\n"
    "Loads octant text (one leaf per line: 'x y z level' in ticks, any order;\n"
    "blank lines and '#' comments ignored) into the octant table of database\n"
    "directory DB, created if absent.  Rejects malformed lines, coordinates or\n"
    "levels out of range, misaligned corners, duplicate and overlapping octants,\n"
    "naming the line; on any error the database is left as it was.\n"
    "  --memory BYTES  memory budget, e.g. 256M or 2G (default 256M): the table\n"
    "                  caches and the LSM's memtable and run caches.  Octants\n"
    "                  in key order are appended as they come; from the first\n"
    "                  one out of order on, the rest go through an LSM store\n"
    "                  (runs spilled in the database directory) and are merged\n"
    "                  in at the end\n"
    "  --tick METRES   size of one tick in metres (default: that of the octant\n"
    "                  table being replaced, else 1)\n"
    "  --origin X,Y,Z  position of tick (0,0,0) in metres (default: that of the\n"
    "                  table being replaced, else 0,0,0)\n"
    "  --plain         write plain leaf pages (default: packed, where keys are\n"
    "                  delta-coded and payload fields stored column-wise)\n"
    "  --quiet         no progress line on stderr (default: octants read and\n"
    "                  their rate, updated on a terminal, every 10 s otherwise)\n";

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

int cmd_import(int argc, char** argv) {
  ParsedArgs args;
  Status st =
      parse_args(argc, argv, 2, {"octants", "memory", "tick", "origin"}, {"plain", "quiet"}, &args);
  if (args.help) return std::fputs(kUsage, stdout), 0;
  if (!st.ok()) return usage_error("import", st.message(), kUsage);
  if (args.positional.size() != 1) return usage_error("import", "expected one DB", kUsage);
  if (!args.values.count("octants"))
    return usage_error("import", "--octants FILE is required", kUsage);
  ImportOptions o;
  o.packed = !args.flags.count("plain");
  st = memory_option(args, &o.memory);
  o.tick_given = args.values.count("tick");
  o.origin_given = args.values.count("origin");
  if (st.ok() && args.values.count("tick")) {
    st = parse_double(args.values["tick"], "--tick", &o.units.tick_m);
    if (st.ok() && !(o.units.tick_m > 0)) st = Status::InvalidArgument("--tick must be positive");
  }
  if (st.ok() && args.values.count("origin")) {
    std::vector<double> v;
    st = parse_double_list(args.values["origin"], "--origin", 3, &v);
    if (st.ok()) o.units.origin_m = {v[0], v[1], v[2]};
  }
  if (!st.ok()) return usage_error("import", st.message(), kUsage);
  const auto t0 = std::chrono::steady_clock::now();
  ProgressLine line(ProgressLine::style_for_stderr(args.flags.count("quiet")), "import", "octants");
  o.progress = line.fn();
  ImportResult r;
  st = import_octants(args.positional[0], args.values["octants"], o, &r);
  line.finish();
  if (!st.ok()) return report("import", st);
  const double secs = seconds_since(t0);
  std::printf(
      "imported %llu octants into %s in %.2fs (%.0f octants/s, %llu LSM runs written, "
      "%.2f bytes/octant)\n",
      (unsigned long long)r.octants, args.positional[0].c_str(), secs, r.octants / secs,
      (unsigned long long)r.runs_spilled, double(r.table_bytes) / r.octants);
  return 0;
}

}  // namespace weaver::cli
