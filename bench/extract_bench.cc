// Extraction throughput: sphere-graded and random octrees (2:1 balanced by
// construction) generated and imported, and the basin model's meshes (built
// by construct and balance: levels graded over 5 and more levels, the
// workload users run), then `weaver extract --json` runs
// in a fresh process per run, so time and peak RSS are what a user sees.  Prints one JSON object
// per run, then a table of medians laid out like the paper's Figure 12. Both algorithms run on
// every mesh; the table adds the speedup of sort over search and the storage of each (Figure 13:
// the node B-tree with element codes vs the node table).
#include <unistd.h>

#include <filesystem>
#include <string>
#include <vector>

#include "basin_stages.h"
#include "bench_util.h"
#include "extract/extract.h"
#include "gen/octree_gen.h"
#include "import/import.h"
#include "import/octant_text.h"

namespace weaver::bench {
namespace {

struct Mesh {
  std::string name;
  GenOptions::Kind kind;
  int max_level;
  double radius;      // sphere
  uint64_t points;    // points
  double basin_freq;  // > 0: the basin model's mesh at this frequency instead
};

// Builds the mesh's octant table in db.
bool build(const Mesh& m, const std::string& dir, const std::string& db) {
  if (m.basin_freq > 0) {
    uint64_t leaves = 0, input = 0;
    return construct_basin(db, m.basin_freq, 2, 256ull << 20, &leaves) &&
           balance_db(db, 256ull << 20, &input, &leaves);
  }
  GenOptions g;
  g.kind = m.kind;
  g.level = 3;
  g.max_level = m.max_level;
  g.radius = m.radius;
  g.points = m.points;
  std::vector<Octant> leaves;
  const std::string text = dir + "/" + m.name + ".txt";
  ImportResult ir;
  const bool ok = generate_octree(g, &leaves).ok() && write_octant_text(text, leaves, "").ok() &&
                  import_octants(db, text, ImportOptions{}, &ir).ok();
  std::filesystem::remove(text);
  return ok;
}

}  // namespace
}  // namespace weaver::bench

int main(int argc, char** argv) {
  using namespace weaver;
  using namespace weaver::bench;
  std::string dir = "/tmp/weaver-extract-bench";
  uint64_t memory = 256ull << 20;
  int repeat = 3;
  int search_repeat = 1;  // the baseline is slow: one run unless asked
  // Sphere-graded and scattered-random octrees, both 2:1 balanced by
  // construction, of about 1M and 10M elements.
  // Sphere-graded and scattered-random octrees, both 2:1 balanced by
  // construction, of about 1M and 10M elements; the basin at 0.2 and 0.5 Hz
  // (0.5M and 11M elements), and 1 Hz (121M) with --large.
  std::vector<Mesh> meshes = {{"graded-1M", GenOptions::Kind::kSphere, 8, 0.3, 0, 0},
                              {"random-1M", GenOptions::Kind::kPoints, 9, 0, 500, 0},
                              {"basin-0.2Hz", GenOptions::Kind::kSphere, 0, 0, 0, 0.2},
                              {"graded-10M", GenOptions::Kind::kSphere, 10, 0.243, 0, 0},
                              {"random-10M", GenOptions::Kind::kPoints, 9, 0, 7200, 0},
                              {"basin-0.5Hz", GenOptions::Kind::kSphere, 0, 0, 0, 0.5}};
  bool cold = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--small")
      meshes.resize(3);
    else if (a == "--large")
      meshes.push_back({"basin-1Hz", GenOptions::Kind::kSphere, 0, 0, 0, 1.0});
    else if (a == "--cold")
      cold = true;
    else if (a == "--repeat" && i + 1 < argc)
      repeat = std::stoi(argv[++i]);
    else if (a == "--search-repeat" && i + 1 < argc)
      search_repeat = std::stoi(argv[++i]);
    else if (a == "--dir" && i + 1 < argc)
      dir = argv[++i];
    else {
      std::printf(
          "usage: extract_bench [--small] [--large (adds the 1 Hz basin)] [--cold] [--repeat N]\n"
          "                     [--search-repeat N (0: no search runs)] [--dir DIR]\n"
          "--cold adds 1-thread sort runs with the database dropped from the page cache first\n");
      return 2;
    }
  }
  std::filesystem::create_directories(dir);
  std::vector<std::map<std::string, std::string>> table;
  for (const Mesh& m : meshes) {
    const std::string db = dir + "/" + m.name + ".db";
    std::filesystem::remove_all(db);
    if (!build(m, dir, db)) {
      std::fprintf(stderr, "cannot build %s\n", m.name.c_str());
      return 1;
    }
    // Write back what generation and import left dirty, so that kernel
    // writeback does not compete with the timed runs for the two cores.
    ::sync();
    double sort_seconds = 0, sort_bytes = 0;
    struct Variant {
      const char* algorithm;
      int threads;
      const char* store;  // of search
      bool cold;          // dropped from the page cache before each run
    };
    std::vector<Variant> variants = {{"sort", 1, "btree", false}, {"sort", 2, "btree", false}};
    if (cold) variants.push_back({"sort", 1, "btree", true});
    if (search_repeat > 0) {  // --search-repeat 0 leaves the baseline out
      variants.push_back({"search", 1, "btree", false});
      variants.push_back({"search", 1, "lsm", false});
    }
    for (const Variant& v : variants) {
      const char* algorithm = v.algorithm;
      const bool search = std::string(algorithm) == "search";
      const int runs = search ? search_repeat : repeat;
      std::vector<double> rates, secs, rss;
      std::map<std::string, std::string> last;
      for (int r = 0; r < runs; ++r) {
        uint64_t peak = 0;
        if (v.cold) drop_page_cache(db);
        std::vector<std::string> args = {WEAVER_BINARY,
                                         "extract",
                                         db,
                                         "--json",
                                         "--algorithm",
                                         algorithm,
                                         "--threads",
                                         std::to_string(v.threads),
                                         "--memory",
                                         std::to_string(memory)};
        if (search) args.insert(args.end(), {"--store", v.store});
        const std::string out = run_program(args, &peak);
        if (out.empty()) {
          std::fprintf(stderr, "weaver extract failed on %s\n", m.name.c_str());
          return 1;
        }
        auto res = parse_flat_json(out);
        Json j;
        j.add("bench", "extract").add("algorithm", algorithm).add("mesh", m.name);
        j.add("store", search ? v.store : "-");
        const double nodes = std::stod(res["nodes"]);
        const double built = std::stod(res[search ? "search_tree_bytes" : "node_table_bytes"]);
        j.add("elements", static_cast<uint64_t>(std::stod(res["elements"])));
        j.add("nodes", static_cast<uint64_t>(nodes));
        j.add("dangling", static_cast<uint64_t>(std::stod(res["edge"]) + std::stod(res["face"])));
        j.add("seconds", std::stod(res["seconds"]))
            .add("nodes_per_s", std::stod(res["nodes_per_s"]));
        j.add("bytes_per_node", std::stod(res["node_table_bytes"]) / nodes);
        // The storage the algorithm builds: the node B-tree with element codes
        // for search, the node table for sort (Figure 13).
        j.add("built_bytes", built).add("built_bytes_per_node", built / nodes);
        j.add("threads", v.threads).add("memory_budget", memory);
        j.add("cache", v.cold ? "cold" : "warm");
        j.add("buckets", static_cast<uint64_t>(std::stod(res["buckets"])));
        j.add("peak_rss_bytes", peak);
        const std::string line = j.str();
        if (line.empty()) return 1;
        std::printf("%s\n", line.c_str());
        last = parse_flat_json(line);
        rates.push_back(std::stod(last["nodes_per_s"]));
        secs.push_back(std::stod(last["seconds"]));
        rss.push_back(std::stod(last["peak_rss_bytes"]));
      }
      last["nodes_per_s"] = fmt(median(rates));
      last["seconds"] = fmt(median(secs));
      last["peak_rss_bytes"] = fmt(median(rss));
      last["runs"] = std::to_string(runs);
      if (v.cold) {
        char buf[64];
        std::snprintf(buf, sizeof buf, "%.2f", std::stod(last["seconds"]) / sort_seconds);
        last["cold_over_warm"] = buf;
      } else if (!search && v.threads == 1) {
        sort_seconds = std::stod(last["seconds"]);
        sort_bytes = std::stod(last["built_bytes"]);
      } else if (!search) {
        char buf[64];
        std::snprintf(buf, sizeof buf, "%.2f", sort_seconds / std::stod(last["seconds"]));
        last["speedup_over_1_thread"] = buf;
      } else {
        char buf[64];
        std::snprintf(buf, sizeof buf, "%.1f", std::stod(last["seconds"]) / sort_seconds);
        last["speedup_of_sort"] = buf;  // over 1-thread sort
        std::snprintf(buf, sizeof buf, "%.1f%%",
                      100.0 * (1 - sort_bytes / std::stod(last["built_bytes"])));
        last["storage_saved_by_sort"] = buf;
      }
      table.push_back(last);
    }
    std::filesystem::remove_all(db);
  }
  std::printf(
      "\nmedians (Figure 12: T and rho per mesh and algorithm; Figure 13: storage built):\n");
  print_table(table, {"mesh", "algorithm", "store", "threads", "cache", "elements", "nodes",
                      "dangling", "seconds", "nodes_per_s", "speedup_over_1_thread",
                      "cold_over_warm", "speedup_of_sort", "built_bytes_per_node",
                      "storage_saved_by_sort", "peak_rss_bytes", "runs"});
  return 0;
}
