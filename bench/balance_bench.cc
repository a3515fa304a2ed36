// `weaver balance` of the basin's unbalanced octree (construct --unbalanced,
// built once a frequency) in windows and by the closure, on 1 and 2
// threads, each run a fresh process on a fresh copy, the four in an order
// that rotates from repeat to repeat; medians of --repeat: seconds, peak
// RSS, what a second thread gives each way, and what auto (windows, on the
// basin) gives against the closure on one thread.  The first repeat checks
// that all four write the same octant table, byte for byte.
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "bench_util.h"

namespace {

using namespace weaver::bench;

struct Way {
  std::string algorithm;
  int threads;
};

}  // namespace

int main(int argc, char** argv) {
  std::vector<double> freqs = {0.5, 1.0};
  int repeat = 3;
  std::string memory = "256M", dir = "/tmp/weaver-balance-bench";
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--freq" && i + 1 < argc) {
      freqs = number_list(argv[++i]);
    } else if (a == "--repeat" && i + 1 < argc) {
      repeat = std::stoi(argv[++i]);
    } else if (a == "--memory" && i + 1 < argc) {
      memory = argv[++i];
    } else if (a == "--dir" && i + 1 < argc) {
      dir = argv[++i];
    } else {
      std::printf(
          "usage: balance_bench [--freq F[,F...]] (default 0.5,1) [--repeat N] [--memory BYTES]\n"
          "                     [--dir DIR]\n");
      return a == "--help" ? 0 : 2;
    }
  }
  std::filesystem::create_directories(dir);
  const std::string weaver = WEAVER_BINARY;
  const std::vector<Way> ways = {{"closure", 1}, {"closure", 2}, {"windows", 1}, {"windows", 2}};
  std::vector<std::map<std::string, std::string>> rows;
  for (double f : freqs) {
    const std::string input = dir + "/input.db", run = dir + "/run.db";
    std::filesystem::remove_all(input);
    if (run_program({weaver, "construct", input, "--model", "basin", "--freq", fmt(f),
                     "--unbalanced", "--quiet"},
                    nullptr)
            .empty()) {
      return 1;
    }
    std::vector<std::vector<double>> secs(ways.size()), rss(ways.size());
    std::vector<std::string> tables(ways.size());
    std::string how;
    bool identical = true;
    for (int r = 0; r < repeat; ++r) {
      for (size_t k = 0; k < ways.size(); ++k) {
        const size_t w = (k + r) % ways.size();
        std::filesystem::remove_all(run);
        std::filesystem::copy(input, run, std::filesystem::copy_options::recursive);
        uint64_t peak = 0;
        const double t0 = now_seconds();
        const std::string out =
            run_program({weaver, "balance", run, "--algorithm", ways[w].algorithm, "--threads",
                         std::to_string(ways[w].threads), "--memory", memory, "--quiet"},
                        &peak);
        secs[w].push_back(now_seconds() - t0);
        rss[w].push_back(peak / 1e6);
        if (out.empty()) return 1;
        if (ways[w].algorithm == "windows" &&
            out.find("leaves read around them") == std::string::npos) {
          how = "windows gave up";
        }
        if (r == 0) {
          const std::string keep = dir + "/table-" + std::to_string(w);
          std::filesystem::copy_file(octant_table(run), keep,
                                     std::filesystem::copy_options::overwrite_existing);
          tables[w] = keep;
        }
        Json j;
        j.add("freq", f).add("repeat", r).add("algorithm", ways[w].algorithm);
        j.add("threads", ways[w].threads).add("seconds", secs[w].back());
        j.add("peak_rss_mb", rss[w].back());
        std::printf("%s\n", j.str().c_str());
      }
    }
    for (size_t w = 1; w < ways.size(); ++w)
      identical = identical && same_bytes(tables[0], tables[w]);
    auto m = [&](size_t w) { return median(secs[w]); };
    rows.push_back(
        {{"freq", fmt(f)},
         {"closure 1/2 s", fmt(m(0)) + " / " + fmt(m(1))},
         {"windows 1/2 s", fmt(m(2)) + " / " + fmt(m(3))},
         {"2nd thread closure", fmt(m(0) / m(1))},
         {"2nd thread windows", fmt(m(2) / m(3))},
         {"closure 1 / windows 2", fmt(m(0) / m(3))},
         {"RSS MB c1/c2/w1/w2", fmt(median(rss[0])) + " / " + fmt(median(rss[1])) + " / " +
                                    fmt(median(rss[2])) + " / " + fmt(median(rss[3]))},
         {"same table", identical ? "yes" : "NO"},
         {"note", how}});
    std::filesystem::remove_all(run);
    std::filesystem::remove_all(input);
    for (const std::string& t : tables) std::filesystem::remove(t);
  }
  std::printf("\nmedians of %d runs a way, in rotating order; --memory %s\n", repeat,
              memory.c_str());
  print_table(rows,
              {"freq", "closure 1/2 s", "windows 1/2 s", "2nd thread closure", "2nd thread windows",
               "closure 1 / windows 2", "RSS MB c1/c2/w1/w2", "same table", "note"});
  return 0;
}
