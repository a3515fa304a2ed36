#include <chrono>
#include <cstdio>

#include "balance/balance.h"
#include "cli/cli.h"
#include "util/progress.h"

namespace weaver::cli {
namespace {

constexpr char kUsage[] =
    "usage: weaver balance DB [--algorithm auto|windows|closure] [--model db:PATH]\n"
    "                         [--memory BYTES] [--threads N] [--check] [--quiet]\n"
    "\n"
    "Replaces the octant table of DB by its minimal face+edge 2:1 balanced\n"
    "refinement: every leaf is kept or split, and nothing is split unless the\n"
    "2:1 condition forces it, also next to holes in the domain (the leaves\n"
    "need not fill their parents).  Out of core; split children take their\n"
    "material from the model that built the table, or from their parent.\n"
    "The new table keeps the old one's leaf page format (packed or plain).\n"
    "  --algorithm A    how; every way writes the same table:\n"
    "                   windows: the leaves in runs of consecutive keys, each\n"
    "                     balanced in memory, on its own thread, against the\n"
    "                     leaves around it (its insulation layer), read from\n"
    "                     the table; a run that does not fit in the memory,\n"
    "                     even as one leaf, falls back to the closure\n"
    "                   closure: the octants the balance requires, level by\n"
    "                     level from fine to coarse, each level sorted out of\n"
    "                     core, then one pass splitting the leaves\n"
    "                   auto (default): windows, or the closure where a\n"
    "                     window's layer outweighs the window (coarse leaves\n"
    "                     among fine ones)\n"
    "  --model db:PATH  the model database the octants were built from, where it\n"
    "                   is not DB's own model table: split leaves take their\n"
    "                   material from it (the octant table names it by its\n"
    "                   source's file name and a digest, never by a path)\n"
    "  --check          only verify; name the first violation (exit status 1 if\n"
    "                   the octree is not balanced)\n"
    "  --memory BYTES   memory budget (default 256M): the table caches, and the\n"
    "                   windows in flight (half of it: their leaves, layers and\n"
    "                   refinements), or the buffers and sorter of the closure\n"
    "  --threads N      windows balanced at once, the table written beside\n"
    "                   them; or threads for the closure's neighbour generation\n"
    "                   and sorts, and (N > 1) one more writing the new table\n"
    "                   beside its final pass (default: the number of cores);\n"
    "                   the table is the same for every N\n"
    "  --quiet          no progress line on stderr (default: one that updates\n"
    "                   itself on a terminal, a line every 10 s otherwise; its\n"
    "                   percent weighs the first pass over the leaves 13%, the\n"
    "                   level passes 46% (by the leaves one level finer) and\n"
    "                   the final pass 41%)\n";

}  // namespace

int cmd_balance(int argc, char** argv) {
  ParsedArgs args;
  Status st = parse_args(argc, argv, 2, {"algorithm", "model", "memory", "threads"},
                         {"check", "quiet"}, &args);
  if (args.help) return std::fputs(kUsage, stdout), 0;
  if (!st.ok()) return usage_error("balance", st.message(), kUsage);
  if (args.positional.size() != 1) return usage_error("balance", "expected one DB", kUsage);
  BalanceOptions o;
  o.check_only = args.flags.count("check") != 0;
  st = memory_option(args, &o.memory);
  if (st.ok()) st = threads_option(args, default_threads(), &o.threads);
  if (st.ok()) st = balance_algorithm_option(args, &o.algorithm);
  if (st.ok()) st = balance_model_option(args, &o.model_dirs);
  if (!st.ok()) return usage_error("balance", st.message(), kUsage);
  const auto t0 = std::chrono::steady_clock::now();
  ProgressLine line(ProgressLine::style_for_stderr(args.flags.count("quiet")), "balance", "leaves");
  o.progress = line.fn();
  BalanceResult r;
  st = balance_octree(args.positional[0], o, &r);
  line.finish();
  if (!st.ok()) return report("balance", st);
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (o.check_only) {
    if (!r.balanced) {
      std::fprintf(stderr, "weaver balance: not 2:1 balanced: %s\n", r.violation.c_str());
      return 1;
    }
    std::printf("%llu leaves, 2:1 balanced (checked in %.2fs)\n",
                (unsigned long long)r.input_leaves, secs);
    return 0;
  }
  char how[96];
  if (r.by_windows) {
    std::snprintf(how, sizeof how, "in %llu window%s, %llu leaves read around them",
                  (unsigned long long)r.windows, r.windows == 1 ? "" : "s",
                  (unsigned long long)r.layer_leaves);
  } else {
    std::snprintf(how, sizeof how, "by the closure of %llu required octants",
                  (unsigned long long)r.required);
  }
  std::printf("balanced %llu leaves into %llu (%llu split, %s) in %.2fs (%.0f leaves/s)\n",
              (unsigned long long)r.input_leaves, (unsigned long long)r.output_leaves,
              (unsigned long long)r.split, how, secs, r.input_leaves / secs);
  return 0;
}

}  // namespace weaver::cli
