// The paper's Figures 11 to 13 reproduced on our synthetic basin model, with
// the paper's numbers (the SCEC Los Angeles basin, a 1 GHz Pentium III)
// beside ours, plus every stage's time, rate, peak RSS and disk.
//
// For each frequency (0.2, 0.5 and 1 Hz; 2 Hz with --large) it runs the whole
// pipeline: construct and balance in child processes of this one (library
// calls), then `weaver extract --json` with the sort on 1 thread and on
// --threads, and the search baseline (the node B-tree; at 1 and 2 Hz only with
// --search-large, as it takes hours there).  Each run prints a JSON line; the
// tables follow.  One run per configuration: at these sizes a run is minutes.
#include <unistd.h>

#include <filesystem>
#include <string>
#include <vector>

#include "basin_stages.h"
#include "bench_util.h"

namespace weaver::bench {
namespace {

using Row = std::map<std::string, std::string>;

// The paper's figures, by frequency: 0.2, 0.5, 1, 2 Hz.
struct PaperColumn {
  double freq;
  const char *elements, *nodes, *danglings;
  const char *search_t, *search_rate, *sort_t, *sort_rate, *speedup;
  const char *search_bytes, *sort_bytes, *saved;
};
const PaperColumn kPaper[] = {
    {0.2, "433k", "556k", "125k", "0:00:28", "19.8k", "0:00:03", "185k", "9.3", "104mb", "10.1mb",
     "85.3%"},
    {0.5, "9.92m", "11.3m", "1.43m", "0:12:59", "14.5k", "0:01:03", "166k", "11.5", "2.17gb",
     "206mb", "90.5%"},
    {1, "113m", "134m", "20m", "2:51:57", "13.0k", "0:14:19", "152k", "12.0", "25.1gb", "2.44gb",
     "90.3%"},
    {2, "1.22b", "1.37b", "147m", "n/a", "n/a", "2:38:44", "144k", "n/a", "n/a", "25.0gb", "n/a"},
};

// A number the way the paper writes it, three significant digits and a
// lower-case suffix per factor 1000: counts as "1.23m", bytes as "1.51gb".
constexpr const char* kCountUnits[] = {"", "k", "m", "b", "t"};
constexpr const char* kByteUnits[] = {"b", "kb", "mb", "gb", "tb"};
std::string paper_text(double v, const char* const (&units)[5]) {
  int u = 0;
  while (v >= 1000 && u < 4) v /= 1000, ++u;
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g%s", v, units[u]);
  return buf;
}
std::string short_count(double v) { return paper_text(v, kCountUnits); }
std::string bytes_text(double bytes) { return paper_text(bytes, kByteUnits); }

// Under a minute as "1.52s", else as the paper writes it, "0:12:59".
std::string clock_text(double seconds) {
  char buf[32];
  if (seconds < 60) {
    std::snprintf(buf, sizeof buf, "%.2fs", seconds);
    return buf;
  }
  const long s = static_cast<long>(seconds + 0.5);
  std::snprintf(buf, sizeof buf, "%ld:%02ld:%02ld", s / 3600, s / 60 % 60, s % 60);
  return buf;
}

// The bytes of the files of one table (name-N.bt) in a database directory.
double table_bytes(const std::string& db, const std::string& table) {
  double bytes = 0;
  for (const auto& e : std::filesystem::directory_iterator(db)) {
    const std::string name = e.path().filename().string();
    if (name.rfind(table + "-", 0) == 0) bytes += double(e.file_size());
  }
  return bytes;
}

// Construct or balance in a child process: its JSON line, empty on failure.
std::string stage_in_child(const char* stage, const std::string& db, double freq, int threads,
                           uint64_t memory) {
  return run_in_child([&](Json* j) {
    const double t0 = now_seconds();
    uint64_t count = 0, input = 0;
    const bool ok = std::string(stage) == "construct"
                        ? construct_basin(db, freq, threads, memory, &count)
                        : balance_db(db, memory, &input, &count);
    if (!ok) return false;
    const double t = now_seconds() - t0;
    j->add("bench", "paper").add("stage", stage).add("freq", freq).add("threads", threads);
    j->add("leaves", count).add("seconds", t).add("leaves_per_s", count / t);
    j->add("memory_budget", memory).add("octant_table_bytes", table_bytes(db, "octants"));
    return true;
  });
}

// `weaver extract --json` with these arguments: its fields plus peak RSS.
Row extract(const std::string& db, const std::vector<std::string>& extra, double freq) {
  std::vector<std::string> args = {WEAVER_BINARY, "extract", db, "--json", "--quiet"};
  args.insert(args.end(), extra.begin(), extra.end());
  uint64_t rss = 0;
  const std::string out = run_program(args, &rss);
  if (out.empty()) return {};
  Row r = parse_flat_json(out);
  r["peak_rss_bytes"] = fmt(double(rss));
  std::printf(
      "{\"bench\": \"paper\", \"stage\": \"extract\", \"freq\": %g, \"peak_rss_bytes\": %llu, %s\n",
      freq, (unsigned long long)rss, out.substr(out.find('{') + 1).c_str());
  return r;
}

}  // namespace
}  // namespace weaver::bench

int main(int argc, char** argv) {
  using namespace weaver;
  using namespace weaver::bench;
  std::vector<double> freqs = {0.2, 0.5, 1.0};
  bool search_large = false;
  int threads = 2;
  uint64_t memory = 256ull << 20;
  std::string dir = "/tmp/weaver-paper-bench";
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--large") {
      freqs.push_back(2.0);
    } else if (a == "--small") {
      freqs = {0.2, 0.5};
    } else if (a == "--search-large") {
      search_large = true;
    } else if (a == "--threads" && i + 1 < argc) {
      threads = std::stoi(argv[++i]);
    } else if (a == "--memory-mb" && i + 1 < argc) {
      memory = std::stoull(argv[++i]) << 20;
    } else if (a == "--dir" && i + 1 < argc) {
      dir = argv[++i];
    } else {
      std::printf(
          "usage: paper_bench [--small (0.2, 0.5 Hz) | --large (adds 2 Hz)] [--search-large]\n"
          "                   [--threads N (default 2)] [--memory-mb M (default 256)] [--dir "
          "DIR]\n");
      return 2;
    }
  }
  std::filesystem::create_directories(dir);
  std::vector<Row> fig11, fig12, fig13, stages;
  for (double f : freqs) {
    const std::string db = dir + "/basin-" + fmt(f) + ".db";
    std::filesystem::remove_all(db);
    const std::string c = stage_in_child("construct", db, f, threads, memory);
    ::sync();
    const std::string b = c.empty() ? "" : stage_in_child("balance", db, f, 1, memory);
    ::sync();
    if (c.empty() || b.empty()) {
      std::fprintf(stderr, "paper_bench: the pipeline failed at %g Hz\n", f);
      return 1;
    }
    std::printf("%s\n%s\n", c.c_str(), b.c_str());
    const std::string mem = std::to_string(memory);
    Row s1 = extract(db, {"--threads", "1", "--memory", mem}, f);
    Row sn = extract(db, {"--threads", std::to_string(threads), "--memory", mem}, f);
    Row se;
    if (f <= 0.5 || search_large) se = extract(db, {"--algorithm", "search", "--memory", mem}, f);
    if (s1.empty() || sn.empty()) return 1;
    const PaperColumn* paper = nullptr;
    for (const PaperColumn& p : kPaper) {
      if (p.freq == f) paper = &p;
    }
    const std::string hz = fmt(f) + " Hz";
    const double nodes = std::stod(s1["nodes"]);
    const double danglings = std::stod(s1["edge"]) + std::stod(s1["face"]);
    fig11.push_back({{"mesh", hz},
                     {"elements", short_count(std::stod(s1["elements"]))},
                     {"nodes", short_count(nodes)},
                     {"danglings", short_count(danglings)},
                     {"paper_elements", paper->elements},
                     {"paper_nodes", paper->nodes},
                     {"paper_danglings", paper->danglings}});
    const double t1 = std::stod(s1["seconds"]), tn = std::stod(sn["seconds"]);
    Row r12 = {{"mesh", hz},
               {"nodes", short_count(nodes)},
               {"sort_T", clock_text(t1)},
               {"sort_rho", short_count(nodes / t1)},
               {"sort_T_threads", clock_text(tn)},
               {"sort_rho_threads", short_count(nodes / tn)},
               {"paper_sort_T", paper->sort_t},
               {"paper_sort_rho", paper->sort_rate},
               {"search_T", "not run"},
               {"paper_search_T", paper->search_t},
               {"paper_search_rho", paper->search_rate},
               {"paper_speedup", paper->speedup}};
    const double sort_bytes = std::stod(s1["node_table_bytes"]);
    Row r13 = {{"mesh", hz},
               {"sort_actual", bytes_text(sort_bytes)},
               {"sort_bytes_per_node", fmt(sort_bytes / nodes)},
               {"paper_sort_actual", paper->sort_bytes},
               {"search_actual", "not run"},
               {"paper_search_actual", paper->search_bytes},
               {"paper_saved", paper->saved}};
    if (!se.empty()) {
      const double ts = std::stod(se["seconds"]), search_bytes = std::stod(se["search_tree_bytes"]);
      r12["search_T"] = clock_text(ts);
      r12["search_rho"] = short_count(nodes / ts);
      r12["speedup"] = fmt(ts / t1);
      r13["search_actual"] = bytes_text(search_bytes);
      r13["saved"] = fmt(100 * (1 - sort_bytes / search_bytes)) + "%";
    }
    fig12.push_back(r12);
    fig13.push_back(r13);
    auto cj = parse_flat_json(c), bj = parse_flat_json(b);
    stages.push_back({{"mesh", hz},
                      {"construct_s", fmt(std::stod(cj["seconds"]))},
                      {"construct_per_s", short_count(std::stod(cj["leaves_per_s"]))},
                      {"construct_rss", bytes_text(std::stod(cj["peak_rss_bytes"]))},
                      {"balance_s", fmt(std::stod(bj["seconds"]))},
                      {"balance_per_s", short_count(std::stod(bj["leaves_per_s"]))},
                      {"balance_rss", bytes_text(std::stod(bj["peak_rss_bytes"]))},
                      {"extract_s", fmt(tn)},
                      {"extract_per_s", short_count(nodes / tn)},
                      {"extract_rss", bytes_text(std::stod(sn["peak_rss_bytes"]))},
                      {"total_s", fmt(std::stod(cj["seconds"]) + std::stod(bj["seconds"]) + tn)},
                      {"octant_table", bytes_text(table_bytes(db, "octants"))},
                      {"node_table", bytes_text(sort_bytes)}});
    std::filesystem::remove_all(db);
  }
  std::printf("\nFigure 11: the meshes (ours: the synthetic basin; paper: SCEC LA basin)\n");
  print_table(fig11, {"mesh", "elements", "nodes", "danglings", "paper_elements", "paper_nodes",
                      "paper_danglings"});
  std::printf(
      "\nFigure 12: extraction time T (h:mm:ss) and rate rho (nodes/s); sort on 1 thread "
      "and on %d; speedup = search T / sort T (1 thread)\n",
      threads);
  print_table(fig12, {"mesh", "nodes", "sort_T", "sort_rho", "sort_T_threads", "sort_rho_threads",
                      "paper_sort_T", "paper_sort_rho", "search_T", "search_rho", "speedup",
                      "paper_search_T", "paper_search_rho", "paper_speedup"});
  std::printf(
      "\nFigure 13: storage built (sort: the packed node table; search: the node "
      "B-tree with element codes)\n");
  print_table(fig13, {"mesh", "sort_actual", "sort_bytes_per_node", "paper_sort_actual",
                      "search_actual", "paper_search_actual", "saved", "paper_saved"});
  std::printf(
      "\nStages (construct on %d threads, balance on 1, extract on %d; budget %llu MB "
      "each):\n",
      threads, threads, (unsigned long long)(memory >> 20));
  print_table(stages, {"mesh", "construct_s", "construct_per_s", "construct_rss", "balance_s",
                       "balance_per_s", "balance_rss", "extract_s", "extract_per_s", "extract_rss",
                       "total_s", "octant_table", "node_table"});
  return 0;
}
