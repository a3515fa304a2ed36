#include <chrono>
#include <cstdio>
#include <memory>

#include "cli/cli.h"
#include "util/progress.h"
#include "verify/verify.h"

namespace weaver::cli {
namespace {

constexpr char kUsage[] =
    "usage: weaver verify DB [--storage-only] [--independent] [--memory BYTES] [--threads N]\n"
    "                        [--quiet]\n"
    "\n"
    "Checks database DB and reports every problem it finds (up to 20), naming\n"
    "the table, page, key, element or node.  Exit status 0 only when all hold.\n"
    "  storage  every page checksum, key order, separators and subtree counts,\n"
    "           the record counts; octant keys valid and not overlapping, with\n"
    "           the per-level counts the metadata claims; node keys and kinds\n"
    "  mesh     (when octants and nodes are both present) 2:1 balance; the node\n"
    "           table against the nodes derived again from the octants by the\n"
    "           extractor's bucket sort, record by record (a node that differs\n"
    "           is then classified from the leaves around it, for the reason);\n"
    "           every dangling node's anchors present and anchored\n"
    "  derived  the aggregate table summarised again from the octants; and\n"
    "           unless --storage-only, the boundary table derived again, record\n"
    "           by record, and under a ground every solid fraction in (0, 1]\n"
    "           and no element wholly above the ground\n"
    "  --storage-only   skip the mesh checks\n"
    "  --independent    classify every node again from the leaves around it (8\n"
    "                   lookups a node, a few times slower) rather than derive the\n"
    "                   nodes again with the extractor's code\n"
    "  --memory BYTES   memory budget (default 256M): the table caches, and half\n"
    "                   for the balance check's out-of-core sort, then the nodes\n"
    "                   derived again\n"
    "  --threads N      threads for the storage check (a table each at a time),\n"
    "                   the boundary check and the node check (default: the\n"
    "                   number of cores); the same report for every N\n"
    "  --quiet          no progress line on stderr for the mesh check (default: nodes\n"
    "                   checked of the node table, updated on a terminal, every 10 s\n"
    "                   otherwise); the line per finished check is always printed\n";

}  // namespace

int cmd_verify(int argc, char** argv) {
  ParsedArgs args;
  Status st = parse_args(argc, argv, 2, {"memory", "threads"},
                         {"storage-only", "independent", "quiet"}, &args);
  if (args.help) return std::fputs(kUsage, stdout), 0;
  if (!st.ok()) return usage_error("verify", st.message(), kUsage);
  if (args.positional.size() != 1) return usage_error("verify", "expected one DB", kUsage);
  VerifyOptions o;
  o.mesh = args.flags.count("storage-only") == 0;
  o.independent = args.flags.count("independent") != 0;
  st = memory_option(args, &o.memory);
  if (st.ok()) st = threads_option(args, default_threads(), &o.threads);
  if (!st.ok()) return usage_error("verify", st.message(), kUsage);
  o.progress = [](const std::string& line) {
    std::printf("%s\n", line.c_str()), std::fflush(stdout);
  };
  const auto t0 = std::chrono::steady_clock::now();
  // Made when the node check starts (its first report), so that its rate
  // and time left count the node check alone, not the checks before it.
  std::unique_ptr<ProgressLine> line;
  const ProgressLine::Style style = ProgressLine::style_for_stderr(args.flags.count("quiet"));
  o.nodes_progress = [&line, style](uint64_t items, double fraction) {
    if (!line) line = std::make_unique<ProgressLine>(style, "verify", "nodes");
    line->update(items, fraction);
  };
  VerifyReport r;
  st = verify_database(args.positional[0], o, &r);
  if (line) line->finish();
  if (!st.ok()) return report("verify", st);
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  for (const std::string& p : r.problems) std::fprintf(stderr, "problem: %s\n", p.c_str());
  if (!r.ok()) {
    std::fprintf(stderr, "weaver verify: %zu problem%s found%s\n", r.problems.size(),
                 r.problems.size() == 1 ? "" : "s",
                 r.problems.size() >= o.max_problems ? " (stopped looking)" : "");
    return 1;
  }
  std::printf("verified %llu tables, %llu records, %llu pages%s in %.2fs: no problems\n",
              (unsigned long long)r.tables, (unsigned long long)r.records,
              (unsigned long long)r.pages, r.mesh_checked ? " and the mesh" : "", secs);
  return 0;
}

}  // namespace weaver::cli
