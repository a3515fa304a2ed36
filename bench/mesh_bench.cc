// The mesh pipeline on the basin model: construct and balance throughput and
// peak RSS (each stage in its own process), extraction through the weaver
// binary, each on one core (pinned), 1 thread and 2 threads (rates and
// speedups against both baselines), and the paper's Figure 11 table
// (elements, nodes, danglings) for our synthetic basin at each frequency.  Medians of --repeat
// runs.  --weaver BINARY runs another build's extract on the same octrees (construct and balance
// are this one's).
#include <unistd.h>

#include <array>
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
  std::vector<std::map<std::string, std::string>> table, scaling;
  for (double f : freqs) {
    const std::string db = dir + "/basin-" + fmt(f) + ".db";
    // Per stage, rates by run kind: one core (pinned, 1 thread), 1 thread, 2 threads.
    enum Run { kOneCore, kT1, kT2, kRuns };
    const char* const run_names[kRuns] = {"one_core", "t1", "t2"};
    std::map<std::string, std::array<std::vector<double>, kRuns>> rates;
    std::vector<double> c_rss, b_rss, e2_rss;
    std::map<std::string, std::string> last_b, last_e;
    auto record = [&](const char* stage, Run run, const std::string& json, const char* rate) {
      std::printf("%s\n", json.c_str());
      auto fields = parse_flat_json(json);
      rates[stage][run].push_back(std::stod(fields[rate]));
      return fields;
    };
    for (int r = 0; r < repeat; ++r) {
      std::filesystem::remove_all(db);
      // Construct on one core, 1 and 2 threads (the same table; the last is kept).
      auto construct = [&](Run run) {
        return run_in_child([&](Json* j) {
          if (run == kOneCore && !pin_to_one_core()) return false;
          const int threads = run == kT2 ? 2 : 1;
          std::filesystem::remove_all(db);
          uint64_t leaves = 0;
          const double t0 = now_seconds();
          if (!construct_basin(db, f, threads, memory, &leaves)) return false;
          const double t = now_seconds() - t0;
          j->add("bench", "mesh").add("stage", "construct").add("model", "basin").add("freq", f);
          j->add("threads", threads).add("one_core", run == kOneCore ? 1 : 0);
          j->add("elements", leaves).add("seconds", t);
          j->add("elements_per_s", leaves / t).add("memory_budget", memory);
          return true;
        });
      };
      for (Run run : {kOneCore, kT1, kT2}) {
        const std::string c = construct(run);
        if (c.empty()) return 1;
        const auto fields = record("construct", run, c, "elements_per_s");
        if (run == kT2) c_rss.push_back(std::stod(fields.at("peak_rss_bytes")));
      }
      // Balance on one core and 1 thread (copies), then on 2 (the table kept).
      auto balance = [&](const std::string& path, Run run) {
        ::sync();
        return run_in_child([&](Json* j) {
          if (run == kOneCore && !pin_to_one_core()) return false;
          BalanceOptions o;
          o.memory = MemoryBudget(memory);
          o.threads = run == kT2 ? 2 : 1;
          BalanceResult res;
          const double t0 = now_seconds();
          if (!balance_octree(path, o, &res).ok()) return false;
          const double t = now_seconds() - t0;
          j->add("bench", "mesh").add("stage", "balance").add("model", "basin").add("freq", f);
          j->add("threads", o.threads).add("one_core", run == kOneCore ? 1 : 0);
          j->add("elements", res.input_leaves).add("balanced_elements", res.output_leaves);
          j->add("seconds", t).add("elements_per_s", res.input_leaves / t);
          j->add("memory_budget", memory);
          return true;
        });
      };
      for (Run run : {kOneCore, kT1, kT2}) {
        const std::string copy = db + ".copy";
        std::filesystem::remove_all(copy);
        if (run != kT2) std::filesystem::copy(db, copy);
        const std::string b = balance(run == kT2 ? db : copy, run);
        std::filesystem::remove_all(copy);
        if (b.empty()) return 1;
        last_b = record("balance", run, b, "elements_per_s");
        if (run == kT2) b_rss.push_back(std::stod(last_b["peak_rss_bytes"]));
      }
      for (Run run : {kOneCore, kT1, kT2}) {
        ::sync();
        uint64_t rss = 0;
        const std::string threads = run == kT2 ? "2" : "1";
        const std::string e = run_program({weaver, "extract", db, "--json", "--threads", threads},
                                          &rss, "", run == kOneCore);
        if (e.empty()) return 1;
        last_e = record("extract", run, e, "nodes_per_s");
        if (run == kT2) e2_rss.push_back(double(rss));
      }
    }
    const double danglings = std::stod(last_e["edge"]) + std::stod(last_e["face"]);
    std::printf(
        "{\"bench\": \"mesh\", \"figure\": 11, \"model\": \"basin\", \"freq\": %g, "
        "\"elements\": %s, \"nodes\": %s, \"danglings\": %.0f}\n",
        f, last_b["balanced_elements"].c_str(), last_e["nodes"].c_str(), danglings);
    auto m = [&](const char* stage, Run run) { return median(rates[stage][run]); };
    std::map<std::string, std::string> row;
    row["freq_hz"] = fmt(f);
    row["elements"] = last_b["balanced_elements"];
    row["nodes"] = last_e["nodes"];
    row["danglings"] = fmt(danglings);
    row["construct_t2_per_s"] = fmt(m("construct", kT2));
    row["construct_rss"] = fmt(median(c_rss));
    row["balance_t2_per_s"] = fmt(m("balance", kT2));
    row["balance_rss"] = fmt(median(b_rss));
    row["extract_t1_per_s"] = fmt(m("extract", kT1));
    row["extract_t2_per_s"] = fmt(m("extract", kT2));
    row["extract_t2_rss"] = fmt(median(e2_rss));
    table.push_back(row);
    for (const char* stage : {"construct", "balance", "extract"}) {
      std::map<std::string, std::string> s;
      s["freq_hz"] = fmt(f);
      s["stage"] = stage;
      for (Run run : {kOneCore, kT1, kT2})
        s[std::string(run_names[run]) + "_per_s"] = fmt(m(stage, run));
      s["t2_vs_t1"] = fmt(m(stage, kT2) / m(stage, kT1));
      s["t2_vs_one_core"] = fmt(m(stage, kT2) / m(stage, kOneCore));
      std::printf(
          "{\"bench\": \"mesh\", \"scaling\": \"%s\", \"freq\": %g, \"one_core_per_s\": %s, "
          "\"t1_per_s\": %s, \"t2_per_s\": %s, \"t2_vs_t1\": %s, \"t2_vs_one_core\": %s}\n",
          stage, f, s["one_core_per_s"].c_str(), s["t1_per_s"].c_str(), s["t2_per_s"].c_str(),
          s["t2_vs_t1"].c_str(), s["t2_vs_one_core"].c_str());
      scaling.push_back(s);
    }
    std::filesystem::remove_all(db);
  }
  std::printf(
      "\nFigure 11 for the synthetic basin (10 points per wavelength), and stage medians of "
      "%d runs:\n",
      repeat);
  print_table(table, {"freq_hz", "elements", "nodes", "danglings", "construct_t2_per_s",
                      "construct_rss", "balance_t2_per_s", "balance_rss", "extract_t1_per_s",
                      "extract_t2_per_s", "extract_t2_rss"});
  std::printf(
      "\nScaling: rates on one core (the process pinned to one CPU, 1 thread), with 1 thread "
      "(on\nany core) and with 2 threads:\n");
  print_table(scaling, {"freq_hz", "stage", "one_core_per_s", "t1_per_s", "t2_per_s", "t2_vs_t1",
                        "t2_vs_one_core"});
  std::printf(
      "paper (SCEC LA basin): 0.2 Hz 433k / 556k / 125k; 0.5 Hz 9.92m / 11.3m / 1.43m; "
      "1 Hz 113m / 134m / 20m; 2 Hz 1.22b / 1.37b / 147m\n");
  return 0;
}
