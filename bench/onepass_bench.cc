// The balanced construct (one pass: construct/subtree_balance.h) against
// the two passes it replaces (construct --unbalanced, then balance), on the
// basin model, each command a fresh `weaver` process, the two in
// alternating order, medians of --repeat: seconds, the ratio, peak RSS, and
// the disk each needs at its peak (the two passes hold both octant tables
// at the end of balance).  The first repeat checks that both write the same
// octant table, byte for byte.
//
// --mesh runs `weaver mesh` and `weaver mesh --unbalanced` too, sampling
// the database directory's size every 0.2 s: end-to-end seconds, each
// stage's seconds, peak disk against the final database, and the bytes the
// run wrote (from its summary).
#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "bench_util.h"

namespace {

using namespace weaver::bench;

uint64_t directory_bytes(const std::string& dir) {
  uint64_t n = 0;
  std::error_code ec;
  for (const auto& e : std::filesystem::recursive_directory_iterator(dir, ec)) {
    if (e.is_regular_file(ec)) n += e.file_size(ec);
  }
  return n;
}

// The largest size the directory reached while fn ran (sampled).
template <typename Fn>
uint64_t peak_disk_while(const std::string& dir, Fn fn) {
  std::atomic<bool> done{false};
  std::atomic<uint64_t> peak{0};
  std::thread sampler([&] {
    while (!done) {
      peak = std::max<uint64_t>(peak, directory_bytes(dir));
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
    }
  });
  fn();
  done = true;
  sampler.join();
  return std::max<uint64_t>(peak, directory_bytes(dir));
}

// The seconds a stage line of `weaver mesh` gives ("construct  N leaves  12.3s ...").
double stage_seconds(const std::string& out, const std::string& stage) {
  std::istringstream in(out);
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind(stage + " ", 0) != 0) continue;
    std::istringstream words(line);
    std::string w;
    while (words >> w) {
      if (w.size() > 1 && w.back() == 's' && std::isdigit(w[0])) return std::stod(w);
    }
  }
  return 0;
}

// The bytes the run wrote, from the summary's "the run wrote X MB".
double written_mb(const std::string& out) {
  const size_t at = out.find("the run wrote ");
  return at == std::string::npos ? 0 : std::stod(out.substr(at + 14));
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<double> freqs = {0.5, 1.0};
  int repeat = 3, threads = 2;
  std::string memory = "256M", dir = "/tmp/weaver-onepass-bench";
  bool mesh = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--freq" && i + 1 < argc) {
      freqs = number_list(argv[++i]);
    } else if (a == "--repeat" && i + 1 < argc) {
      repeat = std::stoi(argv[++i]);
    } else if (a == "--threads" && i + 1 < argc) {
      threads = std::stoi(argv[++i]);
    } else if (a == "--memory" && i + 1 < argc) {
      memory = argv[++i];
    } else if (a == "--dir" && i + 1 < argc) {
      dir = argv[++i];
    } else if (a == "--mesh") {
      mesh = true;
    } else {
      std::printf(
          "usage: onepass_bench [--freq F[,F...]] (default 0.5,1) [--repeat N] [--threads T]\n"
          "                     [--memory BYTES] [--dir DIR] [--mesh]\n");
      return a == "--help" ? 0 : 2;
    }
  }
  std::filesystem::create_directories(dir);
  const std::string weaver = WEAVER_BINARY;
  std::vector<std::map<std::string, std::string>> rows, mesh_rows;
  for (double f : freqs) {
    const std::string one = dir + "/onepass.db", two = dir + "/twopass.db";
    const std::vector<std::string> common = {"--model",  "basin",     "--freq",
                                             fmt(f),     "--threads", std::to_string(threads),
                                             "--memory", memory,      "--quiet"};
    auto with = [&](std::vector<std::string> head, std::vector<std::string> tail = {}) {
      head.insert(head.end(), common.begin(), common.end());
      head.insert(head.end(), tail.begin(), tail.end());
      return head;
    };
    std::vector<double> t_one, t_construct, t_balance, rss_one, rss_two, disk_one, disk_two;
    bool identical = true;
    uint64_t leaves = 0;
    for (int r = 0; r < repeat; ++r) {
      std::filesystem::remove_all(one);
      std::filesystem::remove_all(two);
      auto run_one = [&] {
        uint64_t rss = 0;
        double t0 = now_seconds();
        const uint64_t disk = peak_disk_while(one, [&] {
          run_program(with({weaver, "construct", one}), &rss);
        });
        t_one.push_back(now_seconds() - t0);
        rss_one.push_back(rss / 1e6);
        disk_one.push_back(disk / 1e9);
      };
      auto run_two = [&] {
        uint64_t rss_c = 0, rss_b = 0;
        double t0 = now_seconds(), t1 = 0;
        const uint64_t disk = peak_disk_while(two, [&] {
          run_program(with({weaver, "construct", two}, {"--unbalanced"}), &rss_c);
          t1 = now_seconds();
          run_program({weaver, "balance", two, "--threads", std::to_string(threads), "--memory",
                       memory, "--quiet"},
                      &rss_b);
        });
        t_construct.push_back(t1 - t0);
        t_balance.push_back(now_seconds() - t1);
        rss_two.push_back(std::max(rss_c, rss_b) / 1e6);
        disk_two.push_back(disk / 1e9);
      };
      if (r % 2 == 0)
        run_one(), run_two();
      else
        run_two(), run_one();
      if (r == 0) identical = same_bytes(octant_table(one), octant_table(two));
      const std::string stat = run_program({weaver, "stat", one, "--json"}, nullptr);
      const size_t at = stat.find("\"records\": ");
      if (at != std::string::npos) leaves = std::stoull(stat.substr(at + 11));
      Json j;
      j.add("freq", f).add("repeat", r).add("onepass_s", t_one.back());
      j.add("construct_unbalanced_s", t_construct.back()).add("balance_s", t_balance.back());
      j.add("ratio", (t_construct.back() + t_balance.back()) / t_one.back());
      j.add("onepass_peak_disk_gb", disk_one.back()).add("twopass_peak_disk_gb", disk_two.back());
      std::printf("%s\n", j.str().c_str());
    }
    const double two_s = median(t_construct) + median(t_balance);
    rows.push_back({{"freq", fmt(f)},
                    {"leaves", std::to_string(leaves)},
                    {"one pass s", fmt(median(t_one))},
                    {"construct s", fmt(median(t_construct))},
                    {"balance s", fmt(median(t_balance))},
                    {"two passes s", fmt(two_s)},
                    {"speedup", fmt(two_s / median(t_one))},
                    {"RSS MB 1/2", fmt(median(rss_one)) + " / " + fmt(median(rss_two))},
                    {"peak disk GB 1/2", fmt(median(disk_one)) + " / " + fmt(median(disk_two))},
                    {"same table", identical ? "yes" : "NO"}});
    std::filesystem::remove_all(one);
    std::filesystem::remove_all(two);
    if (!mesh) continue;
    std::vector<double> m_total[2], m_construct[2], m_extract[2], m_disk[2], m_final[2],
        m_written[2];
    for (int r = 0; r < repeat; ++r) {
      for (int k = 0; k < 2; ++k) {
        const int kind = r % 2 == 0 ? k : 1 - k;  // 0: one pass, 1: --unbalanced
        const std::string db = dir + "/mesh.db";
        std::filesystem::remove_all(db);
        std::string out;
        const double t0 = now_seconds();
        const uint64_t disk = peak_disk_while(db, [&] {
          out = run_program(
              with({weaver, "mesh", db}, kind == 1 ? std::vector<std::string>{"--unbalanced"}
                                                   : std::vector<std::string>{}),
              nullptr);
        });
        m_total[kind].push_back(now_seconds() - t0);
        m_construct[kind].push_back(stage_seconds(out, "construct") +
                                    stage_seconds(out, "balance"));
        m_extract[kind].push_back(stage_seconds(out, "extract"));
        m_disk[kind].push_back(disk / 1e9);
        m_final[kind].push_back(directory_bytes(db) / 1e9);
        m_written[kind].push_back(written_mb(out) / 1e3);
        Json j;
        j.add("freq", f).add("mesh", kind == 0 ? "one pass" : "--unbalanced").add("repeat", r);
        j.add("seconds", m_total[kind].back()).add("peak_disk_gb", m_disk[kind].back());
        j.add("final_gb", m_final[kind].back()).add("written_gb", m_written[kind].back());
        std::printf("%s\n", j.str().c_str());
        std::filesystem::remove_all(db);
      }
    }
    for (int kind = 0; kind < 2; ++kind) {
      mesh_rows.push_back(
          {{"freq", fmt(f)},
           {"weaver mesh", kind == 0 ? "one pass" : "--unbalanced"},
           {"seconds", fmt(median(m_total[kind]))},
           {"construct+balance s", fmt(median(m_construct[kind]))},
           {"extract s", fmt(median(m_extract[kind]))},
           {"peak disk GB", fmt(median(m_disk[kind]))},
           {"final GB", fmt(median(m_final[kind]))},
           {"peak/final", fmt(median(m_disk[kind]) / median(m_final[kind]))},
           {"written/final", fmt(median(m_written[kind]) / median(m_final[kind]))}});
    }
  }
  std::printf("\nbasin, %d threads, --memory %s, medians of %d\n", threads, memory.c_str(), repeat);
  print_table(rows, {"freq", "leaves", "one pass s", "construct s", "balance s", "two passes s",
                     "speedup", "RSS MB 1/2", "peak disk GB 1/2", "same table"});
  if (mesh) {
    std::printf("\n");
    print_table(mesh_rows, {"freq", "weaver mesh", "seconds", "construct+balance s", "extract s",
                            "peak disk GB", "final GB", "peak/final", "written/final"});
  }
  return 0;
}
