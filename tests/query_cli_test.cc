// `weaver query` as a user runs it: batches of points from a file or stdin
// in every output mode, bad lines, and the neighbourhood queries' rows.
#include <gtest/gtest.h>

#include <array>
#include <fstream>
#include <set>
#include <sstream>

#include "cli_run.h"
#include "gen/octree_gen.h"
#include "reference/reference_mesh.h"
#include "test_mesh.h"

namespace weaver {
namespace {

using testing::run;

std::vector<std::string> split_lines(const std::string& s) {
  std::vector<std::string> out;
  std::istringstream in(s);
  for (std::string line; std::getline(in, line);) out.push_back(line);
  return out;
}

std::vector<std::string> fields(const std::string& line, char sep) {
  std::vector<std::string> out;
  std::string f;
  std::istringstream in(line);
  while (std::getline(in, f, sep)) out.push_back(f);
  if (!line.empty() && line.back() == sep) out.push_back("");
  return out;
}

class QueryCli : public ::testing::Test {
 protected:
  void SetUp() override {
    leaves_ = testing::small_sphere();
    db_ = testing::build_mesh(leaves_, dir_);
  }
  int64_t containing(uint64_t x, uint64_t y, uint64_t z) const {
    for (size_t j = 0; j < leaves_.size(); ++j) {
      if (x < kRootEdge && y < kRootEdge && z < kRootEdge &&
          octant_contains_point(leaves_[j], {uint32_t(x), uint32_t(y), uint32_t(z)}))
        return int64_t(j);
    }
    return -1;
  }
  testing::TempDir dir_;
  std::vector<Octant> leaves_;
  std::string db_;
};

TEST_F(QueryCli, PointsFileRowsComeInInputOrderWithBadLinesNamed) {
  const std::string pts = dir_.file("p.txt");
  std::ofstream(pts) << "# receivers\n"
                     << "1000 2000 3000\n"
                     << "\n"
                     << "524288,524288,7\n"          // commas
                     << "1 2\n"                      // too few: line 5
                     << "5000000 0 0\n"              // past the root: outside
                     << "12 x 4\n"                   // line 7
                     << "  1048575\t1048575 0  \n";  // tabs and spaces
  for (const char* mode : {"csv", "tsv", "json", "text"}) {
    const auto r = run("query " + db_ + " locate --points " + pts + " --format " + mode);
    EXPECT_EQ(r.code, 1) << mode << r.err;  // bad lines make the exit status non-zero
    EXPECT_NE(r.err.find(pts + ":5: expected 3 numbers"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(pts + ":7: 'x' is not a whole number"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("2 of 6 lines were not points"), std::string::npos) << r.err;
    std::vector<std::string> rows = split_lines(r.out);
    if (std::string(mode) != "json") rows.erase(rows.begin());  // the header
    ASSERT_EQ(rows.size(), 6u) << mode << "\n" << r.out;
    const uint64_t want[6][3] = {{1000, 2000, 3000}, {524288, 524288, 7}, {0, 0, 0},
                                 {5000000, 0, 0},    {0, 0, 0},           {1048575, 1048575, 0}};
    const char* status[6] = {"inside", "inside", "bad", "outside", "bad", "inside"};
    for (size_t i = 0; i < 6; ++i) {
      const std::string& row = rows[i];
      EXPECT_NE(row.find(status[i]), std::string::npos) << mode << " row " << i << ": " << row;
      if (std::string(mode) == "csv") {
        const auto f = fields(row, ',');
        ASSERT_EQ(f.size(), 10u) << row;  // x y z status element level edge corner (no material)
        if (std::string(status[i]) == "bad") continue;
        EXPECT_EQ(f[0], std::to_string(want[i][0]));
        const int64_t id = containing(want[i][0], want[i][1], want[i][2]);
        EXPECT_EQ(f[4], id < 0 ? "" : std::to_string(id)) << row;
        if (id >= 0) {
          EXPECT_EQ(f[5], std::to_string(leaves_[id].level));
        }
      }
    }
  }
}

TEST_F(QueryCli, NodeAtFromStdinAndMetres) {
  // node 0 sits at the origin; in metres with tick 1 m, 0.5 m floors to tick 0.
  const auto r = run("query " + db_ + " node-at --points - --format csv --units m",
                     "printf '0 0 0\\n0.5 0.5 0.5\\n1 1 1\\n' | ");
  EXPECT_EQ(r.code, 0) << r.err;
  const auto rows = split_lines(r.out);
  ASSERT_EQ(rows.size(), 4u) << r.out;
  EXPECT_EQ(rows[0], "x,y,z,status,node,kind");
  EXPECT_EQ(rows[1], "0,0,0,node,0,anchored");
  EXPECT_EQ(rows[2], "0.5,0.5,0.5,node,0,anchored");
  EXPECT_EQ(rows[3], "1,1,1,none,,");
  const auto m = run("query " + db_ + " material 1 2 3");
  EXPECT_EQ(m.code, 1);
  EXPECT_NE(m.err.find("no material"), std::string::npos) << m.err;
}

// A batch shared among threads (an Explorer each, lookups split by input
// order, rows formatted a slice a thread) prints what one thread prints,
// byte for byte: batches of 100K points (several per file, each past the
// size that is shared), slices of 32K rows, bad lines and points outside
// mixed in; and its rows are the reference's.
TEST_F(QueryCli, ThreadsShareABatchAndPrintTheSameRows) {
  const std::string pts = dir_.file("many.txt");
  std::vector<std::array<uint64_t, 3>> asked;
  {
    std::ofstream out(pts);
    uint64_t state = 12345;
    const auto next = [&state] {
      return (state = state * 6364136223846793005ull + 1442695040888963407ull) >> 33;
    };
    for (size_t i = 0; i < 250000; ++i) {
      if (i % 9973 == 0) {
        out << "not a point\n";
        continue;
      }
      // Every fourth point on a coarse lattice, where nodes are; some past the root.
      const uint64_t c[3] = {next() % (kRootEdge + 4096), next() % kRootEdge, next() % kRootEdge};
      const uint64_t mask = i % 4 == 0 ? ~uint64_t{0xFFFF} : ~uint64_t{0};
      out << (c[0] & mask) << ' ' << (c[1] & mask) << ' ' << (c[2] & mask) << '\n';
      asked.push_back({c[0] & mask, c[1] & mask, c[2] & mask});
    }
  }
  for (const char* query : {"locate", "node-at"}) {
    for (const char* mode : {"csv", "json", "jsonl", "text"}) {
      std::string one;
      for (const char* threads : {"1", "2", "3"}) {
        const auto r = run("query " + db_ + " " + query + " --points " + pts + " --format " + mode +
                           " --memory 64M --threads " + threads);
        EXPECT_EQ(r.code, 1) << r.err;  // the bad lines
        EXPECT_NE(r.err.find("26 of 250000 lines were not points"), std::string::npos) << r.err;
        if (std::string(threads) == "1") {
          one = r.out;
          continue;
        }
        EXPECT_TRUE(r.out == one) << query << " " << mode << " at " << threads << " threads";
      }
      if (std::string(query) != "locate" || std::string(mode) != "csv") continue;
      // Every 97th point's element against the reference.
      std::vector<std::string> rows = split_lines(one);
      rows.erase(rows.begin());
      ASSERT_EQ(rows.size(), 250000u);
      size_t k = 0;
      for (size_t i = 0; i < rows.size(); ++i) {
        if (i % 9973 == 0) continue;
        const auto p = asked[k++];
        if (k % 97 != 0) continue;
        const int64_t id = containing(p[0], p[1], p[2]);
        EXPECT_EQ(fields(rows[i], ',')[4], id < 0 ? "" : std::to_string(id)) << rows[i];
      }
    }
  }
}

TEST_F(QueryCli, ARangeToTheFarFaceOfTheAddressSpaceIsTheWholeMesh) {
  // A box drawn to the domain's far edge ends at tick 2^20, where no pixel
  // is: it holds what a box to 2^20 - 1 holds, and one tick more is refused.
  const auto whole = run("query " + db_ + " range 0 0 0 1048576 1048576 1048576");
  ASSERT_EQ(whole.code, 0) << whole.err;
  EXPECT_EQ(whole.out, std::to_string(leaves_.size()) + " leaves intersect the box\n");
  const auto face = run("query " + db_ + " range 0 0 1048576 1048576 1048576 1048576");
  const auto before = run("query " + db_ + " range 0 0 1048575 1048575 1048575 1048575");
  EXPECT_EQ(face.out, before.out);
  const auto past = run("query " + db_ + " range 0 0 0 1048577 1048576 1048576");
  EXPECT_NE(past.code, 0);
  EXPECT_NE(past.err.find("outside the address space"), std::string::npos) << past.err;
}

TEST_F(QueryCli, NeighbourhoodsPrintOneRowEach) {
  const reference::Mesh ref = reference::extract(leaves_);
  const auto n = run("query " + db_ + " neighbors 3 --all --format csv");
  ASSERT_EQ(n.code, 0) << n.err;
  size_t want = 0;
  for (size_t j = 0; j < leaves_.size(); ++j) {
    want += j != 3 && reference::face_or_edge_adjacent(leaves_[3], leaves_[j]);
  }
  // Corner neighbours too: every leaf whose closed box meets element 3's.
  size_t corner_only = 0;
  for (size_t j = 0; j < leaves_.size(); ++j) {
    const Octant &a = leaves_[3], &b = leaves_[j];
    const int64_t ea = octant_edge(a), eb = octant_edge(b);
    bool touch = j != 3;
    const int64_t alo[3] = {a.x, a.y, a.z}, blo[3] = {b.x, b.y, b.z};
    for (int k = 0; k < 3; ++k)
      touch = touch && std::max(alo[k], blo[k]) <= std::min(alo[k] + ea, blo[k] + eb);
    corner_only += touch && !reference::face_or_edge_adjacent(a, b);
  }
  // A leaf may lie across several directions (a larger one across a face and
  // its edges): the rows are at least the distinct leaves that touch.
  std::set<std::string> ids;
  const auto rows = split_lines(n.out);
  for (size_t i = 1; i < rows.size(); ++i) ids.insert(fields(rows[i], ',')[2]);
  EXPECT_EQ(ids.size(), want + corner_only) << n.out;
  const auto e = run("query " + db_ + " node-elements 0 --format json");
  ASSERT_EQ(e.code, 0) << e.err;
  EXPECT_EQ(e.out, "[{\"element\": 0, \"corner\": 0, \"x\": 0, \"y\": 0, \"z\": 0, \"level\": " +
                       std::to_string(leaves_[0].level) +
                       ", \"edge\": " + std::to_string(octant_edge(leaves_[0])) + "}]\n");
  const auto bad = run("query " + db_ + " depends 99999999");
  EXPECT_EQ(bad.code, 1);
  EXPECT_NE(bad.err.find("node 99999999 does not exist"), std::string::npos) << bad.err;
  EXPECT_EQ(run("query " + db_ + " neighbors").code, 2);
}

}  // namespace
}  // namespace weaver
