// Transform throughput: the basin model's meshes (0.2 and 0.5 Hz; 1 Hz with
// --large) exported to every format by `weaver export` in a fresh process
// per run, as a user runs it: elements per second, bytes written and their
// rate, and peak RSS at a fixed --memory.  Also `weaver partition` (sfc, and
// graph through gpmetis when it is on the PATH) and the per-part raw export.
// Prints one JSON object per run, then a table of medians.
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "basin_stages.h"
#include "bench_util.h"

namespace weaver::bench {
namespace {

uint64_t bytes_under(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::is_directory(path, ec)) return fs::file_size(path, ec);
  uint64_t n = 0;
  for (const auto& e : fs::recursive_directory_iterator(path, ec)) {
    if (e.is_regular_file(ec)) n += e.file_size(ec);
  }
  return n;
}

struct Job {
  std::string name;               // in the table
  std::vector<std::string> args;  // after "weaver"
  std::string out;                // what it writes ("" for none)
};

}  // namespace
}  // namespace weaver::bench

int main(int argc, char** argv) {
  using namespace weaver;
  using namespace weaver::bench;
  std::string dir = "/tmp/weaver-export-bench";
  uint64_t memory = 256ull << 20;
  int repeat = 3;
  std::vector<double> freqs = {0.2, 0.5};
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--small") {
      freqs = {0.2};
    } else if (a == "--large") {
      freqs.push_back(1.0);
    } else if (a == "--repeat" && i + 1 < argc) {
      repeat = std::stoi(argv[++i]);
    } else if (a == "--dir" && i + 1 < argc) {
      dir = argv[++i];
    } else {
      std::printf(
          "usage: export_bench [--small] [--large (adds the 1 Hz basin)] [--repeat N]"
          " [--dir DIR]\n");
      return 2;
    }
  }
  const bool metis = std::system("command -v gpmetis > /dev/null 2>&1") == 0;
  std::filesystem::create_directories(dir);
  std::vector<std::map<std::string, std::string>> table;
  for (double freq : freqs) {
    const std::string mesh = "basin-" + fmt(freq) + "Hz";
    const std::string db = dir + "/" + mesh + ".db";
    std::filesystem::remove_all(db);
    uint64_t leaves = 0, input = 0;
    uint64_t peak = 0;
    if (!construct_basin(db, freq, 2, memory, &leaves) ||
        !balance_db(db, memory, &input, &leaves) ||
        run_program({WEAVER_BINARY, "extract", db, "--quiet"}, &peak).empty()) {
      std::fprintf(stderr, "cannot build %s\n", mesh.c_str());
      return 1;
    }
    const std::string o = dir + "/out";
    std::vector<Job> jobs = {
        {"vtu", {"export", db, "--format", "vtu", "--out", o + ".vtu"}, o + ".vtu"},
        {"raw", {"export", db, "--format", "raw", "--out", o + ".raw"}, o + ".raw"},
        {"msh", {"export", db, "--format", "msh", "--out", o + ".msh"}, o + ".msh"},
        {"metis", {"export", db, "--format", "metis", "--out", o + ".graph"}, o + ".graph"},
        {"csv", {"export", db, "--format", "csv", "--out", o + ".csv"}, o + ".csv"},
        {"pvtu 8", {"export", db, "--format", "pvtu", "--parts", "8", "--out", o + ".pvtu"}, o},
        {"partition sfc 8", {"partition", db, "--parts", "8"}, ""},
        {"raw parts 8",
         {"export", db, "--format", "raw", "--parts", "8", "--out", o + ".parts"},
         o + ".parts"}};
    if (metis)
      jobs.push_back(
          {"partition graph 8", {"partition", db, "--parts", "8", "--method", "graph"}, ""});
    ::sync();
    for (const Job& job : jobs) {
      std::vector<double> secs, rss;
      std::map<std::string, std::string> last;
      for (int r = 0; r < repeat; ++r) {
        std::vector<std::string> args = {WEAVER_BINARY};
        args.insert(args.end(), job.args.begin(), job.args.end());
        args.insert(args.end(), {"--memory", std::to_string(memory), "--quiet"});
        const double t0 = now_seconds();
        const std::string out = run_program(args, &peak);
        const double s = now_seconds() - t0;
        if (out.empty()) {
          std::fprintf(stderr, "failed: weaver %s on %s\n", job.name.c_str(), mesh.c_str());
          return 1;
        }
        const uint64_t bytes = job.out.empty() ? 0 : bytes_under(job.out);
        Json j;
        j.add("bench", "export").add("mesh", mesh).add("job", job.name);
        j.add("elements", leaves).add("seconds", s).add("elements_per_s", leaves / s);
        j.add("bytes", bytes).add("mb_per_s", bytes / s / 1e6);
        j.add("memory_budget", memory).add("peak_rss_bytes", peak);
        const std::string line = j.str();
        std::printf("%s\n", line.c_str());
        std::fflush(stdout);
        last = parse_flat_json(line);
        secs.push_back(s);
        rss.push_back(double(peak));
      }
      const double s = median(secs);
      last["seconds"] = fmt(s);
      last["elements_per_s"] = fmt(leaves / s);
      last["mb_per_s"] = fmt(std::stod(last["bytes"]) / s / 1e6);
      last["peak_rss_mb"] = fmt(median(rss) / 1e6);
      last["bytes"] = fmt(std::stod(last["bytes"]) / 1e6) + " MB";
      last["runs"] = std::to_string(repeat);
      table.push_back(last);
    }
    std::filesystem::remove_all(db);
    for (const char* x : {".vtu", ".raw", ".msh", ".graph", ".csv", ".pvtu", "", ".parts"}) {
      std::filesystem::remove_all(o + x);
    }
  }
  std::printf("\nmedians of %d runs, --memory %llu MB\n", repeat,
              (unsigned long long)(memory >> 20));
  print_table(table, {"mesh", "job", "elements", "seconds", "elements_per_s", "bytes", "mb_per_s",
                      "peak_rss_mb", "runs"});
  return 0;
}
