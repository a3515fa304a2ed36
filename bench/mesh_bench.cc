// The mesh pipeline on the basin model: construct and balance (1 and 2
// threads each) throughput and peak RSS (each stage in its own process), extraction through the
// weaver binary with 1 and 2 threads (rate, speedup, peak RSS), and the paper's Figure 11 table
// (elements, nodes, danglings) for our synthetic basin at each frequency.  Medians of --repeat
// runs.  --weaver BINARY runs another build's extract on the same octrees (construct and balance
// are this one's).
#include <unistd.h>

#include <filesystem>
#include <string>
#include <vector>

#include "balance/balance.h"
#include "basin_stages.h"
#include "bench_util.h"
#include "construct/construct.h"

int main(int argc, char** argv) {
  using namespace weaver;
  using namespace weaver::bench;
  std::vector<double> freqs = {0.2, 0.5};
  int repeat = 3;
  std::string dir = "/tmp/weaver-mesh-bench";
  const uint64_t memory = 256ull << 20;
  std::string weaver = WEAVER_BINARY;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--large")
      freqs.push_back(1.0);
    else if (a == "--repeat" && i + 1 < argc)
      repeat = std::stoi(argv[++i]);
    else if (a == "--dir" && i + 1 < argc)
      dir = argv[++i];
    else if (a == "--weaver" && i + 1 < argc)
      weaver = argv[++i];
    else {
      std::printf(
          "usage: mesh_bench [--large (adds 1 Hz)] [--repeat N] [--dir DIR] [--weaver BINARY]\n");
      return 2;
    }
  }
  std::filesystem::create_directories(dir);
  std::vector<std::map<std::string, std::string>> table;
  for (double f : freqs) {
    const std::string db = dir + "/basin-" + fmt(f) + ".db";
    std::vector<double> c1_rate, c_rate, c_rss, b1_rate, b_rate, b_rss, e1_rate, e2_rate, e2_rss,
        speedup;
    std::map<std::string, std::string> row, last_c, last_b, last_e;
    for (int r = 0; r < repeat; ++r) {
      std::filesystem::remove_all(db);
      // Construct on 1 and on 2 threads (the same table; the second is kept).
      auto construct = [&](int threads) {
        return run_in_child([&](Json* j) {
          std::filesystem::remove_all(db);
          uint64_t leaves = 0;
          const double t0 = now_seconds();
          if (!construct_basin(db, f, threads, memory, &leaves)) return false;
          const double t = now_seconds() - t0;
          j->add("bench", "mesh").add("stage", "construct").add("model", "basin").add("freq", f);
          j->add("threads", threads).add("elements", leaves).add("seconds", t);
          j->add("elements_per_s", leaves / t).add("memory_budget", memory);
          return true;
        });
      };
      const std::string c1 = construct(1);
      const std::string c = construct(2);
      if (c1.empty() || c.empty()) return 1;
      std::printf("%s\n", c1.c_str());
      c1_rate.push_back(std::stod(parse_flat_json(c1)["elements_per_s"]));
      // Balance on 1 thread (a copy) and on 2 (the table that is kept).
      auto balance = [&](const std::string& path, int threads) {
        ::sync();
        return run_in_child([&](Json* j) {
          BalanceOptions o;
          o.memory = MemoryBudget(memory);
          o.threads = threads;
          BalanceResult res;
          const double t0 = now_seconds();
          if (!balance_octree(path, o, &res).ok()) return false;
          const double t = now_seconds() - t0;
          j->add("bench", "mesh").add("stage", "balance").add("model", "basin").add("freq", f);
          j->add("threads", threads).add("elements", res.input_leaves);
          j->add("balanced_elements", res.output_leaves);
          j->add("seconds", t).add("elements_per_s", res.input_leaves / t);
          j->add("memory_budget", memory);
          return true;
        });
      };
      const std::string copy = db + ".t1";
      std::filesystem::remove_all(copy);
      std::filesystem::copy(db, copy);
      const std::string b1 = balance(copy, 1);
      std::filesystem::remove_all(copy);
      const std::string b = balance(db, 2);
      if (b1.empty()) return 1;
      std::printf("%s\n", b1.c_str());
      b1_rate.push_back(std::stod(parse_flat_json(b1)["elements_per_s"]));
      ::sync();
      uint64_t rss1 = 0, rss2 = 0;
      const std::string e1 =
          run_program({weaver, "extract", db, "--json", "--threads", "1"}, &rss1);
      const std::string e = run_program({weaver, "extract", db, "--json", "--threads", "2"}, &rss2);
      if (c.empty() || b.empty() || e1.empty() || e.empty()) return 1;
      std::printf("%s\n%s\n%s\n%s\n", c.c_str(), b.c_str(), e1.c_str(), e.c_str());
      last_c = parse_flat_json(c);
      last_b = parse_flat_json(b);
      last_e = parse_flat_json(e);
      const double r1 = std::stod(parse_flat_json(e1)["nodes_per_s"]);
      const double r2 = std::stod(last_e["nodes_per_s"]);
      e1_rate.push_back(r1);
      e2_rate.push_back(r2);
      e2_rss.push_back(double(rss2));
      speedup.push_back(r2 / r1);
      c_rate.push_back(std::stod(last_c["elements_per_s"]));
      c_rss.push_back(std::stod(last_c["peak_rss_bytes"]));
      b_rate.push_back(std::stod(last_b["elements_per_s"]));
      b_rss.push_back(std::stod(last_b["peak_rss_bytes"]));
    }
    const double danglings = std::stod(last_e["edge"]) + std::stod(last_e["face"]);
    std::printf(
        "{\"bench\": \"mesh\", \"figure\": 11, \"model\": \"basin\", \"freq\": %g, "
        "\"elements\": %s, \"nodes\": %s, \"danglings\": %.0f}\n",
        f, last_b["balanced_elements"].c_str(), last_e["nodes"].c_str(), danglings);
    row["freq_hz"] = fmt(f);
    row["elements"] = last_b["balanced_elements"];
    row["nodes"] = last_e["nodes"];
    row["danglings"] = fmt(danglings);
    row["construct_t1_per_s"] = fmt(median(c1_rate));
    row["construct_t2_per_s"] = fmt(median(c_rate));
    row["construct_speedup"] = fmt(median(c_rate) / median(c1_rate));
    row["construct_rss"] = fmt(median(c_rss));
    row["balance_t1_per_s"] = fmt(median(b1_rate));
    row["balance_t2_per_s"] = fmt(median(b_rate));
    row["balance_speedup"] = fmt(median(b_rate) / median(b1_rate));
    row["balance_rss"] = fmt(median(b_rss));
    row["extract_t1_per_s"] = fmt(median(e1_rate));
    row["extract_t2_per_s"] = fmt(median(e2_rate));
    row["t2_speedup"] = fmt(median(speedup));
    row["extract_t2_rss"] = fmt(median(e2_rss));
    table.push_back(row);
    std::filesystem::remove_all(db);
  }
  std::printf(
      "\nFigure 11 for the synthetic basin (10 points per wavelength), and stage medians of "
      "%d runs:\n",
      repeat);
  print_table(table, {"freq_hz", "elements", "nodes", "danglings", "construct_t1_per_s",
                      "construct_t2_per_s", "construct_speedup", "construct_rss",
                      "balance_t1_per_s", "balance_t2_per_s", "balance_speedup", "balance_rss",
                      "extract_t1_per_s", "extract_t2_per_s", "t2_speedup", "extract_t2_rss"});
  std::printf(
      "paper (SCEC LA basin): 0.2 Hz 433k / 556k / 125k; 0.5 Hz 9.92m / 11.3m / 1.43m; "
      "1 Hz 113m / 134m / 20m; 2 Hz 1.22b / 1.37b / 147m\n");
  return 0;
}
