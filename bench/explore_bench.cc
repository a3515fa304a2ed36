// Point queries as users ask them, on the basin model's 0.5 Hz mesh (0.2 Hz
// with --small, or any database with --db): a million random points in the
// domain's bounding box answered with material
//   - through the library API (MeshDatabase::locate, the million at once) on
//     1 and 2 threads, points per second;
//   - end to end by `weaver query DB locate --points FILE --format csv` in a
//     fresh process (reading text, answering, writing text);
//   - and by `weaver shell` one query at a time (warm), against one
//     `weaver query` process per question: the median latency of each;
//   - and `weaver slice` of the plane z = 1 km, 2000 pixels wide.
// Prints one JSON object per measurement, then a table of medians.
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "basin_stages.h"
#include "bench_util.h"
#include "query/explorer.h"
#include "weaver/weaver.h"

namespace weaver::bench {
namespace {

struct Box {
  uint32_t lo[3] = {UINT32_MAX, UINT32_MAX, UINT32_MAX}, hi[3] = {0, 0, 0};
};

// The bounding box of the leaves (a scan of the keys).
bool bounding_box(const std::string& db, Box* b) {
  std::unique_ptr<Explorer> ex;
  if (!Explorer::open(db, MemoryBudget(64 << 20), &ex).ok()) return false;
  BTreeCursor c;
  if (!ex->mesh().octants().seek_cursor(0, &c).ok()) return false;
  for (; c.valid(); c.next()) {
    const Octant o = octant_from_key(c.key());
    const uint32_t lo[3] = {o.x, o.y, o.z}, e = octant_edge(o);
    for (int a = 0; a < 3; ++a) {
      b->lo[a] = std::min(b->lo[a], lo[a]);
      b->hi[a] = std::max(b->hi[a], lo[a] + e);
    }
  }
  return true;
}

std::vector<Coord> random_points(const Box& b, size_t n, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<Coord> p(n);
  for (Coord& c : p) {
    c = {uint32_t(b.lo[0] + rng() % (b.hi[0] - b.lo[0])),
         uint32_t(b.lo[1] + rng() % (b.hi[1] - b.lo[1])),
         uint32_t(b.lo[2] + rng() % (b.hi[2] - b.lo[2]))};
  }
  return p;
}

// Runs `weaver shell db` on a script through a pipe and returns what it
// printed ("" if it failed).
std::string run_shell(const std::string& db, const std::string& script, const std::string& dir) {
  const std::string file = dir + "/script.txt";
  {
    std::ofstream f(file);
    f << script;
  }
  uint64_t peak = 0;
  const std::string out_file = dir + "/shell.out";
  const std::string cmd =
      std::string(WEAVER_BINARY) + " shell " + db + " < " + file + " > " + out_file;
  if (std::system(cmd.c_str()) != 0) return "";
  (void)peak;
  std::ifstream in(out_file);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// The "Run Time: real S" values the shell's .timer printed.
std::vector<double> run_times(const std::string& out) {
  std::vector<double> v;
  const std::string tag = "Run Time: real ";
  for (size_t at = 0; (at = out.find(tag, at)) != std::string::npos; at += tag.size()) {
    v.push_back(std::stod(out.substr(at + tag.size())));
  }
  return v;
}

Json row(const std::string& mesh, const std::string& job) {
  Json j;
  j.add("bench", "explore").add("mesh", mesh).add("job", job);
  return j;
}

}  // namespace
}  // namespace weaver::bench

int main(int argc, char** argv) {
  using namespace weaver;
  using namespace weaver::bench;
  std::string dir = "/tmp/weaver-explore-bench", db;
  double freq = 0.5;
  int repeat = 3;
  size_t points = 1000000;
  const uint64_t memory = 256ull << 20;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--small") {
      freq = 0.2, points = 200000;
    } else if (a == "--db" && i + 1 < argc) {
      db = argv[++i];
    } else if (a == "--repeat" && i + 1 < argc) {
      repeat = std::stoi(argv[++i]);
    } else {
      std::printf("usage: explore_bench [--small] [--db DB (an existing mesh)] [--repeat N]\n");
      return 2;
    }
  }
  std::filesystem::create_directories(dir);
  std::string mesh =
      db.empty() ? "basin-" + fmt(freq) + "Hz" : std::filesystem::path(db).filename().string();
  if (db.empty()) {
    db = dir + "/" + mesh + ".db";
    std::filesystem::remove_all(db);
    uint64_t leaves = 0, input = 0, peak = 0;
    if (!construct_basin(db, freq, 2, memory, &leaves) ||
        !balance_db(db, memory, &input, &leaves) ||
        run_program({WEAVER_BINARY, "extract", db, "--quiet"}, &peak).empty()) {
      std::fprintf(stderr, "cannot build %s\n", mesh.c_str());
      return 1;
    }
  }
  Box box;
  if (!bounding_box(db, &box)) return std::fprintf(stderr, "cannot open %s\n", db.c_str()), 1;
  const std::vector<Coord> pts = random_points(box, points, 1);
  const std::string file = dir + "/points.txt";
  {
    std::ofstream f(file);
    for (const Coord& c : pts) f << c.x << ' ' << c.y << ' ' << c.z << '\n';
  }
  std::vector<std::map<std::string, std::string>> table;
  auto report = [&](const std::string& job, const std::string& unit, std::vector<double> rates,
                    double rss) {
    std::map<std::string, std::string> r = {{"mesh", mesh},
                                            {"job", job},
                                            {"median", fmt(median(rates))},
                                            {"unit", unit},
                                            {"runs", std::to_string(rates.size())},
                                            {"peak_rss_mb", fmt(rss / 1e6)}};
    table.push_back(r);
  };

  // The library API (weaver/weaver.h), as a program calls it: the whole
  // million in one locate, on 1 thread and on 2 (open's `threads`), timed
  // inside one process.  The first pass reads the table into the pools; a
  // program that keeps the database open asks at the rate of the next ones
  // (their median).
  std::vector<api::Point> api_points(pts.size());
  for (size_t i = 0; i < pts.size(); ++i) api_points[i] = {pts[i].x, pts[i].y, pts[i].z};
  for (const int threads : {1, 2}) {
    std::vector<double> rates, cold;
    double rss = 0;
    for (int r = 0; r < repeat; ++r) {
      const std::string line = run_in_child([&](Json* j) {
        std::string error;
        auto api_db = api::MeshDatabase::open(db, &error, memory, threads);
        if (!api_db) return false;
        std::vector<api::PointHit> hits(pts.size());
        double first = 0;
        std::vector<double> warm;
        for (int pass = 0; pass < 4; ++pass) {
          const double t0 = now_seconds();
          if (!api_db->locate(api_points.data(), api_points.size(), hits.data())) return false;
          (pass == 0 ? first : warm.emplace_back()) = now_seconds() - t0;
        }
        const double s = median(warm);
        uint64_t inside = 0;
        for (const api::PointHit& h : hits) inside += h.inside;
        *j = row(mesh, "locate api");
        j->add("threads", uint64_t(threads)).add("points", uint64_t(pts.size()));
        j->add("inside", inside).add("seconds", s).add("points_per_s", pts.size() / s);
        j->add("first_pass_points_per_s", pts.size() / first);
        return true;
      });
      if (line.empty()) return 1;
      std::printf("%s\n", line.c_str());
      const auto f = parse_flat_json(line);
      rates.push_back(std::stod(f.at("points_per_s")));
      cold.push_back(std::stod(f.at("first_pass_points_per_s")));
      rss = std::stod(f.at("peak_rss_bytes"));
    }
    const std::string name =
        "locate, C++ API, " + std::to_string(threads) + " thread" + (threads > 1 ? "s" : "");
    report(name, "points/s", rates, rss);
    report(name + ", first pass", "points/s", cold, rss);
  }

  std::vector<double> rates;
  double rss = 0;
  // End to end: text in, text out, one process.
  for (int r = 0; r < repeat; ++r) {
    uint64_t peak = 0;
    const double t0 = now_seconds();
    const std::string out = run_program({WEAVER_BINARY, "query", db, "locate", "--points", file,
                                         "--format", "csv", "--memory", std::to_string(memory)},
                                        &peak, dir + "/answers.csv");
    const double s = now_seconds() - t0;
    if (out.empty()) return 1;
    Json j = row(mesh, "locate --points csv");
    j.add("points", uint64_t(pts.size())).add("seconds", s).add("points_per_s", pts.size() / s);
    j.add("output_bytes", uint64_t(std::filesystem::file_size(dir + "/answers.csv")));
    j.add("peak_rss_bytes", peak);
    std::printf("%s\n", j.str().c_str());
    rates.push_back(pts.size() / s);
    rss = double(peak);
  }
  report("locate --points, end to end", "points/s", rates, rss);
  // One question at a time: in the shell (warm: after a first thousand) and
  // as one `weaver query` process each.
  {
    std::string script = ".timer on\n";
    const size_t questions = 2000;
    for (size_t i = 0; i < questions; ++i) {
      const Coord& c = pts[i];
      script += "locate " + std::to_string(c.x) + " " + std::to_string(c.y) + " " +
                std::to_string(c.z) + "\n";
    }
    const std::vector<double> t = run_times(run_shell(db, script, dir));
    if (t.size() < questions) return std::fprintf(stderr, "the shell failed\n"), 1;
    const std::vector<double> warm(t.begin() + questions / 2, t.begin() + questions);
    const double shell_s = median(warm);
    std::vector<double> process;
    for (size_t i = 0; i < 30; ++i) {
      const Coord& c = pts[i];
      uint64_t peak = 0;
      const double t0 = now_seconds();
      if (run_program({WEAVER_BINARY, "query", db, "locate", std::to_string(c.x),
                       std::to_string(c.y), std::to_string(c.z)},
                      &peak)
              .empty())
        return 1;
      process.push_back(now_seconds() - t0);
    }
    const double process_s = median(process);
    Json j = row(mesh, "single locate");
    j.add("shell_median_us", shell_s * 1e6).add("process_median_us", process_s * 1e6);
    j.add("ratio", process_s / shell_s);
    std::printf("%s\n", j.str().c_str());
    table.push_back({{"mesh", mesh},
                     {"job", "one locate in the shell (warm)"},
                     {"median", fmt(shell_s * 1e6)},
                     {"unit", "us"},
                     {"runs", std::to_string(warm.size())}});
    table.push_back({{"mesh", mesh},
                     {"job", "one locate, a process each"},
                     {"median", fmt(process_s * 1e6)},
                     {"unit", "us"},
                     {"runs", std::to_string(process.size())}});
    table.push_back(
        {{"mesh", mesh}, {"job", "  ratio"}, {"median", fmt(process_s / shell_s)}, {"unit", "x"}});
  }
  // A picture: the plane at z = 1 km, 2000 pixels wide.
  {
    std::vector<double> secs;
    uint64_t peak = 0;
    for (int r = 0; r < repeat; ++r) {
      const double t0 = now_seconds();
      if (run_program({WEAVER_BINARY, "slice", db, "--axis", "z", "--at", "1000", "--units", "m",
                       "--color", "vs", "--width", "2000", "--out", dir + "/slice.png"},
                      &peak)
              .empty())
        return 1;
      secs.push_back(now_seconds() - t0);
      Json j = row(mesh, "slice z=1km 2000px");
      j.add("seconds", secs.back()).add("peak_rss_bytes", peak);
      j.add("png_bytes", uint64_t(std::filesystem::file_size(dir + "/slice.png")));
      std::printf("%s\n", j.str().c_str());
    }
    table.push_back({{"mesh", mesh},
                     {"job", "slice z = 1 km, 2000 px (png)"},
                     {"median", fmt(median(secs))},
                     {"unit", "s"},
                     {"runs", std::to_string(repeat)},
                     {"peak_rss_mb", fmt(peak / 1e6)}});
  }
  std::printf("\nmedians of %d runs, --memory %llu MB, %zu random points\n", repeat,
              (unsigned long long)(memory >> 20), pts.size());
  print_table(table, {"mesh", "job", "median", "unit", "runs", "peak_rss_mb"});
  return 0;
}
