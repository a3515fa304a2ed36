#include <unistd.h>

#include <chrono>
#include <cstdio>

#include "cli/cli.h"
#include "extract/extract.h"
#include "util/progress.h"

namespace weaver::cli {
namespace {

constexpr char kUsage[] =
    "usage: weaver extract DB [--algorithm sort|search] [--store btree|lsm] [--threads N]\n"
    "                         [--buckets leaves|level] [--memory BYTES] [--plain] [--json]\n"
    "                         [--quiet]\n"
    "\n"
    "Extracts the mesh nodes of the balanced octree in DB's octant table into\n"
    "its node table (node key + kind: anchored, edge- or face-dangling; ids are\n"
    "ranks, anchors follow from coordinate and kind), by the two-level bucket\n"
    "sort, out of core.  Refuses overlapping octants and octrees that are not\n"
    "face+edge 2:1 balanced, naming two offending octants; on any error the\n"
    "database is left as it was.\n"
    "  --algorithm sort    the two-level bucket sort (default)\n"
    "  --algorithm search  the conventional baseline: a node B-tree searched for\n"
    "                      every element vertex, holding up to 8 element codes\n"
    "                      per node; slower, same result\n"
    "  --store btree|lsm   the node store of search: a B+tree (default, as in the\n"
    "                      paper) or the LSM store (writes batched in a memtable\n"
    "                      and sorted runs; every lookup may visit each run)\n"
    "  --threads N         worker threads for sort (default: the number of cores);\n"
    "                      the node table is the same for every N\n"
    "  --buckets leaves    sort's high-level buckets hold about the same number of\n"
    "                      leaves each (default; up to 8192 for every MiB of\n"
    "                      the core's L2 cache and 16384 at most, fewer if the\n"
    "                      budget is small), cut at aligned boundaries\n"
    "  --buckets level     the paper's buckets: aligned octants of the coarsest\n"
    "                      level that would fit the budget if filled with leaves\n"
    "                      of the finest level present (slow on graded meshes:\n"
    "                      most buckets then hold a few coarse leaves)\n"
    "  --plain             write the node table with plain leaf pages (default:\n"
    "                      packed, about 0.7 bytes per node)\n"
    "  --json              print the result as one JSON object\n"
    "  --quiet             no progress line on stderr (default: one that updates\n"
    "                      itself on a terminal, a line every 10 s otherwise;\n"
    "                      percent = elements done of the octant table's)\n"
    "  --memory BYTES      memory budget, e.g. 256M (default 256M): the octant and\n"
    "                      node table caches, the high-level buckets (their size\n"
    "                      comes from it), spilled corners held before a file,\n"
    "                      buckets read ahead for the threads; with search, the\n"
    "                      scratch node store's cache or memtable\n";

}  // namespace

int cmd_extract(int argc, char** argv) {
  ParsedArgs args;
  Status st = parse_args(argc, argv, 2, {"memory", "algorithm", "store", "threads", "buckets"},
                         {"json", "plain", "quiet"}, &args);
  if (args.help) return std::fputs(kUsage, stdout), 0;
  if (!st.ok()) return usage_error("extract", st.message(), kUsage);
  if (args.positional.size() != 1) return usage_error("extract", "expected one DB", kUsage);
  ExtractOptions o;
  o.packed = !args.flags.count("plain");
  st = memory_option(args, &o.memory);
  if (st.ok() && args.values.count("algorithm")) {
    const std::string& a = args.values["algorithm"];
    if (a == "search") {
      o.algorithm = ExtractOptions::Algorithm::kSearch;
    } else if (a != "sort") {
      st = Status::InvalidArgument("--algorithm must be sort or search");
    }
  }
  if (st.ok() && args.values.count("store")) {
    const std::string& s = args.values["store"];
    if (s == "lsm") {
      o.store = ExtractOptions::Store::kLsm;
    } else if (s != "btree") {
      st = Status::InvalidArgument("--store must be btree or lsm");
    }
    if (st.ok() && o.algorithm != ExtractOptions::Algorithm::kSearch) {
      st = Status::InvalidArgument("--store applies to --algorithm search only");
    }
  }
  if (st.ok()) st = threads_option(args, default_threads(), &o.threads);
  if (st.ok() && args.values.count("buckets")) {
    const std::string& b = args.values["buckets"];
    if (b == "level") {
      o.buckets = ExtractOptions::Buckets::kLevel;
    } else if (b != "leaves") {
      st = Status::InvalidArgument("--buckets must be leaves or level");
    }
  }
  if (!st.ok()) return usage_error("extract", st.message(), kUsage);
  const auto t0 = std::chrono::steady_clock::now();
  auto elapsed = [t0] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  };
  ProgressLine line(ProgressLine::style_for_stderr(args.flags.count("quiet")), "extract",
                    "elements");
  o.progress = line.fn();
  ExtractResult r;
  st = extract_mesh(args.positional[0], o, &r);
  line.finish();
  if (!st.ok()) return report("extract", st);
  const double secs = elapsed();
  if (args.flags.count("json")) {
    const bool search = o.algorithm == ExtractOptions::Algorithm::kSearch;
    std::printf(
        "{\"algorithm\": \"%s\", \"store\": \"%s\", \"threads\": %d, \"memory_budget\": %llu, "
        "\"elements\": %llu, \"nodes\": %llu, \"anchored\": %llu, \"edge\": %llu, "
        "\"face\": %llu, \"seconds\": %.6f, \"nodes_per_s\": %.1f, \"buckets\": %llu, "
        "\"bucket_level\": %d, \"bucket_leaves\": %llu, \"spilled\": %llu, \"spilled_to_disk\": "
        "%llu, \"node_table_bytes\": %llu, "
        "\"search_tree_bytes\": %llu}\n",
        search ? "search" : "sort", o.store == ExtractOptions::Store::kLsm ? "lsm" : "btree",
        o.threads, (unsigned long long)o.memory.bytes(), (unsigned long long)r.elements,
        (unsigned long long)r.nodes, (unsigned long long)r.anchored, (unsigned long long)r.edge,
        (unsigned long long)r.face, secs, r.nodes / secs, (unsigned long long)r.buckets,
        r.bucket_level, (unsigned long long)r.bucket_leaves, (unsigned long long)r.spilled,
        (unsigned long long)r.spilled_to_disk, (unsigned long long)r.node_table_bytes,
        (unsigned long long)r.search_tree_bytes);
    return 0;
  }
  std::printf(
      "extracted %llu nodes (%llu anchored, %llu edge-dangling, %llu face-dangling) from "
      "%llu elements in %.2fs (%.0f nodes/s)\n",
      (unsigned long long)r.nodes, (unsigned long long)r.anchored, (unsigned long long)r.edge,
      (unsigned long long)r.face, (unsigned long long)r.elements, secs, r.nodes / secs);
  if (o.algorithm == ExtractOptions::Algorithm::kSearch) {
    std::printf("node %s with element codes %.2f bytes/node, node table %.2f bytes/node\n",
                o.store == ExtractOptions::Store::kLsm ? "LSM store" : "B-tree",
                double(r.search_tree_bytes) / r.nodes, double(r.node_table_bytes) / r.nodes);
  } else {
    const std::string buckets = r.bucket_level >= 0
                                    ? "at level " + std::to_string(r.bucket_level)
                                    : "of about " + std::to_string(r.bucket_leaves) + " leaves";
    std::printf(
        "%llu buckets %s, %llu nodal pixels spilled (%llu through the spill log), node "
        "table %.2f bytes/node\n",
        (unsigned long long)r.buckets, buckets.c_str(), (unsigned long long)r.spilled,
        (unsigned long long)r.spilled_to_disk, double(r.node_table_bytes) / r.nodes);
  }
  return 0;
}

}  // namespace weaver::cli
