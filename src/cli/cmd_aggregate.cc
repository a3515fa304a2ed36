#include <chrono>
#include <cstdio>

#include "cli/cli.h"
#include "query/aggregates.h"

namespace weaver::cli {
namespace {

constexpr char kUsage[] =
    "usage: weaver aggregate DB [--max-records N] [--memory BYTES] [--quiet]\n"
    "\n"
    "Builds the aggregate table of database DB: for each octant of the coarse\n"
    "levels that holds elements, how many, their coarsest and finest levels and\n"
    "the least, greatest and mean (by volume) of each material field.  One scan\n"
    "of the octant table; the records are written in key order.  'weaver serve'\n"
    "reads it to show, where a map pixel holds many elements, the least vs (or\n"
    "another summary) of the elements in it instead of the one at its centre.\n"
    "Replacing the octant table (a new mesh) drops the aggregate table; 'weaver\n"
    "verify' computes it again and compares.\n"
    "\n"
    "  --max-records N  keep the levels 0 to the finest whose octants number at\n"
    "                   most N (default: a 64th of the leaves, at least 4M); each\n"
    "                   level more holds up to 8 times the one before, and shows\n"
    "                   one more zoom of serve's maps from the table\n"
    "  --memory BYTES   bounds the table caches, the levels' files' among them\n"
    "                   (default 256M)\n"
    "  --quiet          no progress line on stderr\n";

}  // namespace

int cmd_aggregate(int argc, char** argv) {
  ParsedArgs args;
  Status st = parse_args(argc, argv, 2, {"memory", "max-records"}, {"quiet"}, &args);
  if (args.help) return std::fputs(kUsage, stdout), 0;
  if (!st.ok()) return usage_error("aggregate", st.message(), kUsage);
  if (args.positional.size() != 1) return usage_error("aggregate", "expected one DB", kUsage);
  AggregateOptions o;
  st = memory_option(args, &o.memory);
  if (st.ok() && args.values.count("max-records")) {
    st = parse_count(args.values.at("max-records"), "--max-records", &o.max_records);
    if (st.ok() && o.max_records == 0)
      st = Status::InvalidArgument("--max-records must be positive");
  }
  if (!st.ok()) return usage_error("aggregate", st.message(), kUsage);
  const auto t0 = std::chrono::steady_clock::now();
  AggregateReport r;
  {
    ProgressLine line(ProgressLine::style_for_stderr(args.flags.count("quiet")), "aggregate",
                      "leaves");
    o.progress = line.fn();
    st = build_aggregates(args.positional[0], o, &r);
  }
  if (!st.ok()) return report("aggregate", st);
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("summarised %llu leaves into %llu octants of levels 0 to %d (%llu bytes) in %.2fs\n",
              (unsigned long long)r.leaves, (unsigned long long)r.records, r.finest,
              (unsigned long long)r.bytes, secs);
  return 0;
}

}  // namespace weaver::cli
