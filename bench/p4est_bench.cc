// weaver beside p4est on the same octrees, in one run: p8est's in-memory
// 2:1 balance (face + edge) against `weaver balance`, and p8est_nodes_new /
// p8est_lnodes_new against `weaver extract`, with a check that the balanced
// leaves and the anchored, edge- and face-dangling node counts agree.
// Built only where Debian's libp4est-dev (and MPI's headers) are installed;
// weaver itself never links p4est.  Each side runs in a fresh process, so
// peak RSS is its own.
//   p4est_bench [--small] [--repeat N] [--dir DIR]
#include <mpi.h>
#include <p8est_bits.h>
#include <p8est_extended.h>
#include <p8est_ghost.h>
#include <p8est_lnodes.h>
#include <p8est_nodes.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "bench_util.h"
#include "schema/octant.h"

namespace weaver::bench {
namespace {

// The leaves of an octant text file, sorted by key.
std::vector<uint64_t> read_leaves(const std::string& path) {
  std::vector<uint64_t> keys;
  std::ifstream in(path);
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    uint32_t x, y, z, level;
    if (std::sscanf(line.c_str(), "%u %u %u %u", &x, &y, &z, &level) != 4) continue;
    keys.push_back(octant_key({x, y, z, uint8_t(level)}));
  }
  std::sort(keys.begin(), keys.end());
  return keys;
}

const std::vector<uint64_t>* g_leaves = nullptr;

// Refines a quadrant while some input leaf lies strictly inside it: the
// forest becomes exactly the input octree (p8est's root is 2^19 units,
// weaver's 2^20 ticks, at the same levels).
int refine_to_input(p8est_t*, p4est_topidx_t, p8est_quadrant_t* q) {
  const Coord pixel{uint32_t(q->x) << 1, uint32_t(q->y) << 1, uint32_t(q->z) << 1};
  const auto it = std::upper_bound(g_leaves->begin(), g_leaves->end(), pixel_key(pixel));
  if (it == g_leaves->begin()) return 0;
  return octant_key_level(*(it - 1)) > q->level ? 1 : 0;
}

// The p8est side, in its own process: prints one JSON object.
int run_p8est(const std::string& text, int argc, char** argv) {
  MPI_Init(&argc, &argv);
  sc_init(MPI_COMM_WORLD, 0, 0, nullptr, SC_LP_ERROR);
  p4est_init(nullptr, SC_LP_ERROR);
  const std::vector<uint64_t> leaves = read_leaves(text);
  g_leaves = &leaves;
  p8est_connectivity_t* conn = p8est_connectivity_new_unitcube();
  p8est_t* p = p8est_new_ext(MPI_COMM_WORLD, conn, 0, 0, 1, 0, nullptr, nullptr);
  double t0 = now_seconds();
  p8est_refine(p, 1, refine_to_input, nullptr);
  const double refine_s = now_seconds() - t0;
  const uint64_t input = uint64_t(p->global_num_quadrants);
  t0 = now_seconds();
  p8est_balance(p, P8EST_CONNECT_EDGE, nullptr);
  const double balance_s = now_seconds() - t0;
  const uint64_t balanced = uint64_t(p->global_num_quadrants);
  const uint64_t rss_balance = peak_rss_bytes();
  // Nodes need the ghost layer to find hanging nodes (without one, every
  // node counts as independent); its time is the nodes' time.
  t0 = now_seconds();
  p8est_ghost_t* ghost = p8est_ghost_new(p, P8EST_CONNECT_FULL);
  p8est_nodes_t* nodes = p8est_nodes_new(p, ghost);
  const double nodes_s = now_seconds() - t0;
  const uint64_t indep = nodes->indep_nodes.elem_count, face = nodes->face_hangings.elem_count,
                 edge = nodes->edge_hangings.elem_count;
  p8est_nodes_destroy(nodes);
  t0 = now_seconds();
  p8est_lnodes_t* lnodes = p8est_lnodes_new(p, ghost, 1);
  const double lnodes_s = now_seconds() - t0;
  const uint64_t lnodes_count = uint64_t(lnodes->num_local_nodes);
  p8est_lnodes_destroy(lnodes);
  p8est_ghost_destroy(ghost);
  Json j;
  j.add("input", input).add("refine_s", refine_s).add("balance_s", balance_s);
  j.add("balanced", balanced).add("nodes_s", nodes_s).add("anchored", indep);
  j.add("edge", edge).add("face", face).add("lnodes_s", lnodes_s).add("lnodes", lnodes_count);
  j.add("rss_after_balance", rss_balance).add("peak_rss_bytes", peak_rss_bytes());
  std::printf("%s\n", j.str().c_str());
  p8est_destroy(p);
  p8est_connectivity_destroy(conn);
  sc_finalize();
  MPI_Finalize();
  return 0;
}

struct Case {
  std::string name;
  std::vector<std::string> generate;  // weaver generate's options
};

}  // namespace
}  // namespace weaver::bench

int main(int argc, char** argv) {
  using namespace weaver::bench;
  if (argc >= 3 && std::string(argv[1]) == "--p8est") return run_p8est(argv[2], argc, argv);
  std::string dir = "/tmp/weaver-p4est-bench";
  int repeat = 3;
  bool small = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--small") {
      small = true;
    } else if (a == "--repeat" && i + 1 < argc) {
      repeat = std::stoi(argv[++i]);
    } else if (a == "--dir" && i + 1 < argc) {
      dir = argv[++i];
    } else {
      std::printf("usage: p4est_bench [--small] [--repeat N] [--dir DIR]\n");
      return 2;
    }
  }
  // Unbalanced random refinement (balance has work to do: it grows about
  // fourfold) and graded spheres (balanced already: the nodes are the
  // work), about 1M and 10M leaves once balanced.
  std::vector<Case> cases = {
      {"random 0.25M -> 1M", {"--kind", "random", "--leaves", "250000", "--max-level", "12"}},
      {"sphere 1M", {"--kind", "sphere", "--level", "4", "--max-level", "8"}},
      {"random 2.5M -> 10M", {"--kind", "random", "--leaves", "2500000", "--max-level", "13"}},
      {"sphere 15M", {"--kind", "sphere", "--level", "5", "--max-level", "10"}}};
  if (small) cases.resize(2);
  setenv("OMPI_ALLOW_RUN_AS_ROOT", "1", 1);
  setenv("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1", 1);
  std::filesystem::create_directories(dir);
  std::vector<std::map<std::string, std::string>> table;
  bool all_agree = true;
  for (const Case& c : cases) {
    const std::string text = dir + "/octree.txt", db = dir + "/w.db";
    std::vector<std::string> gen = {WEAVER_BINARY, "generate", text};
    gen.insert(gen.end(), c.generate.begin(), c.generate.end());
    uint64_t peak = 0;
    if (run_program(gen, &peak).empty()) return 1;
    std::vector<double> wb, we, pb, pn, pl;
    uint64_t w_rss_b = 0, w_rss_e = 0, p_rss = 0;
    std::map<std::string, std::string> w, p;
    for (int r = 0; r < repeat; ++r) {
      std::filesystem::remove_all(db);
      if (run_program({WEAVER_BINARY, "import", db, "--octants", text, "--quiet"}, &peak).empty())
        return 1;
      double t0 = now_seconds();
      if (run_program({WEAVER_BINARY, "balance", db, "--quiet"}, &w_rss_b).empty()) return 1;
      wb.push_back(now_seconds() - t0);
      t0 = now_seconds();
      const std::string ex =
          run_program({WEAVER_BINARY, "extract", db, "--json", "--quiet"}, &w_rss_e);
      we.push_back(now_seconds() - t0);
      if (ex.empty()) return 1;
      w = parse_flat_json(ex);
      const std::string side = run_program({argv[0], "--p8est", text}, &p_rss);
      if (side.empty()) return 1;
      p = parse_flat_json(side);
      pb.push_back(std::stod(p["balance_s"]));
      pn.push_back(std::stod(p["nodes_s"]));
      pl.push_back(std::stod(p["lnodes_s"]));
    }
    const bool agree = w["elements"] == p["balanced"] && w["anchored"] == p["anchored"] &&
                       w["edge"] == p["edge"] && w["face"] == p["face"];
    all_agree = all_agree && agree;
    Json j;
    j.add("bench", "p4est").add("case", c.name).add("leaves_in", std::stod(p["input"]));
    j.add("leaves_balanced", std::stod(w["elements"])).add("agree", agree ? "yes" : "NO");
    j.add("weaver_balance_s", median(wb)).add("p8est_balance_s", median(pb));
    j.add("weaver_extract_s", median(we)).add("p8est_nodes_s", median(pn));
    j.add("p8est_lnodes_s", median(pl)).add("lnodes_over_weaver", median(pl) / median(we));
    j.add("weaver_balance_rss", w_rss_b).add("weaver_extract_rss", w_rss_e);
    j.add("p8est_rss", p_rss);
    std::printf("%s\n", j.str().c_str());
    std::printf("  weaver: %s anchored, %s edge, %s face; p8est: %s, %s, %s\n",
                w["anchored"].c_str(), w["edge"].c_str(), w["face"].c_str(), p["anchored"].c_str(),
                p["edge"].c_str(), p["face"].c_str());
    table.push_back({{"case", c.name},
                     {"leaves", w["elements"]},
                     {"agree", agree ? "yes" : "NO"},
                     {"balance w/p s", fmt(median(wb)) + " / " + fmt(median(pb))},
                     {"balance p/w", fmt(median(pb) / median(wb))},
                     {"extract w / nodes / lnodes s",
                      fmt(median(we)) + " / " + fmt(median(pn)) + " / " + fmt(median(pl))},
                     {"nodes p/w", fmt(median(pn) / median(we))},
                     {"lnodes p/w", fmt(median(pl) / median(we))},
                     {"rss w bal/ext MB", fmt(w_rss_b / 1e6) + " / " + fmt(w_rss_e / 1e6)},
                     {"rss p8est MB", fmt(p_rss / 1e6)}});
    std::filesystem::remove_all(db);
  }
  std::printf(
      "\nmedians of %d runs; weaver at its default --memory (256M), p8est in memory, 1 rank\n",
      repeat);
  print_table(table, {"case", "leaves", "agree", "balance w/p s", "balance p/w",
                      "extract w / nodes / lnodes s", "nodes p/w", "lnodes p/w", "rss w bal/ext MB",
                      "rss p8est MB"});
  return all_agree ? 0 : 1;
}
