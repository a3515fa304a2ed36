// A hostile user's probes (issue "Robustness"): each of these lost data,
// left an inconsistent database, crashed or answered wrongly before.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>

#include "cli_run.h"
#include "db/database.h"
#include "util/args.h"

namespace weaver {
namespace {

namespace fs = std::filesystem;
using testing::CommandRun;
using testing::lines;
using testing::run;

class Robustness : public ::testing::Test {
 protected:
  void SetUp() override {
    octants_ = dir_.file("o.txt");
    ASSERT_EQ(run("generate " + octants_ + " --kind sphere --level 2 --max-level 5").code, 0);
    other_ = dir_.file("p.txt");
    ASSERT_EQ(run("generate " + other_ + " --kind points --level 2 --max-level 5").code, 0);
  }
  // A database holding an extracted mesh with 2.5 m ticks.
  std::string mesh_db() {
    const std::string db = dir_.file("mesh.db");
    EXPECT_EQ(run("import " + db + " --octants " + octants_ + " --tick 2.5").code, 0);
    EXPECT_EQ(run("extract " + db).code, 0);
    return db;
  }
  void expect_verifies(const std::string& db) {
    const CommandRun v = run("verify " + db);
    EXPECT_EQ(v.code, 0) << v.out << v.err;
  }
  testing::TempDir dir_;
  std::string octants_, other_;
};

TEST_F(Robustness, ImportOverAMeshDropsTheNodeTableAndKeepsTheUnits) {
  const std::string db = mesh_db();
  const CommandRun imp = run("import " + db + " --octants " + other_);
  ASSERT_EQ(imp.code, 0) << imp.err;
  EXPECT_EQ(lines(imp.err), 1) << imp.err;
  EXPECT_NE(imp.err.find("dropped table 'nodes'"), std::string::npos) << imp.err;
  expect_verifies(db);
  EXPECT_EQ(run("stat " + db).out.find("table nodes"), std::string::npos);
  // "element 0: corner (0 0 0), level L, edge E ticks = M m": M = E x tick.
  auto metres_per_tick = [&] {
    const CommandRun e = run("query " + db + " element 0");
    EXPECT_EQ(e.code, 0) << e.err;
    const size_t edge = e.out.find("edge "), eq = e.out.find("= ");
    if (edge == std::string::npos || eq == std::string::npos) return 0.0;
    return std::stod(e.out.substr(eq + 2)) / std::stod(e.out.substr(edge + 5));
  };
  EXPECT_DOUBLE_EQ(metres_per_tick(), 2.5);
  // An explicit --tick replaces it.
  ASSERT_EQ(run("import " + db + " --octants " + other_ + " --tick 1").code, 0);
  EXPECT_DOUBLE_EQ(metres_per_tick(), 1.0);
}

TEST_F(Robustness, ConstructOverAMeshDropsTheNodeTable) {
  const std::string db = mesh_db();
  const CommandRun c = run("construct " + db + " --model halfspace --freq 0.05");
  ASSERT_EQ(c.code, 0) << c.err;
  EXPECT_NE(c.err.find("dropped table 'nodes'"), std::string::npos) << c.err;
  expect_verifies(db);
}

TEST_F(Robustness, TableFilesWithoutAManifestAreNeverRemovedAndCanBeRecovered) {
  const std::string db = mesh_db();
  const std::string before = run("export " + db + " --nodes " + dir_.file("n0.csv")).err;
  std::vector<std::string> files;
  for (const auto& e : fs::directory_iterator(db)) files.push_back(e.path().filename());
  fs::remove(db + "/MANIFEST");
  for (const char* writer : {"import DB --octants O", "construct DB --model halfspace --freq 0.05",
                             "balance DB", "extract DB"}) {
    std::string args = writer;
    args.replace(args.find("DB"), 2, db);
    if (args.find(" O") != std::string::npos) args.replace(args.find(" O"), 2, " " + other_);
    const CommandRun r = run(args);
    EXPECT_EQ(r.code, 1) << args;
    EXPECT_EQ(lines(r.err), 1) << r.err;
    EXPECT_NE(r.err.find("weaver recover"), std::string::npos) << r.err;
    for (const std::string& f : files) {
      EXPECT_TRUE(f == "MANIFEST" || fs::exists(db + "/" + f)) << args << " removed " << f;
    }
  }
  const CommandRun rec = run("recover " + db);
  ASSERT_EQ(rec.code, 0) << rec.err;
  EXPECT_NE(rec.out.find("recovered table nodes"), std::string::npos) << rec.out;
  expect_verifies(db);
  ASSERT_EQ(run("export " + db + " --nodes " + dir_.file("n1.csv")).code, 0);
  std::ifstream a(dir_.file("n0.csv")), b(dir_.file("n1.csv"));
  EXPECT_TRUE(std::equal(std::istreambuf_iterator<char>(a), {}, std::istreambuf_iterator<char>(b)));
  const CommandRun again = run("recover " + db);
  EXPECT_EQ(again.code, 1) << again.err;  // an intact manifest: refused
  EXPECT_NE(again.err.find("intact"), std::string::npos) << again.err;
}

TEST_F(Robustness, RecoverLeavesOutANodeTableOlderThanItsOctants) {
  const std::string db = mesh_db();
  std::string nodes_file;
  for (const auto& e : fs::directory_iterator(db)) {
    if (e.path().filename().string().rfind("nodes-", 0) == 0) nodes_file = e.path();
  }
  fs::copy_file(nodes_file, dir_.file("saved-nodes"));
  ASSERT_EQ(run("import " + db + " --octants " + other_).code, 0);  // drops the nodes
  fs::copy_file(dir_.file("saved-nodes"), nodes_file);              // a stale one comes back
  {
    std::ofstream(db + "/MANIFEST", std::ios::app) << "garbage";  // damaged
  }
  const CommandRun rec = run("recover " + db);
  ASSERT_EQ(rec.code, 0) << rec.err;
  EXPECT_NE(rec.out.find("MANIFEST.damaged"), std::string::npos) << rec.out;
  EXPECT_NE(rec.out.find("older than the table 'octants'"), std::string::npos) << rec.out;
  EXPECT_TRUE(fs::exists(nodes_file + ".unused"));
  expect_verifies(db);
  EXPECT_EQ(run("stat " + db).out.find("table nodes"), std::string::npos);
}

TEST_F(Robustness, ManifestProblemsAreNamed) {
  const std::string db = mesh_db();
  { std::ofstream(db + "/MANIFEST", std::ios::app) << "x"; }
  CommandRun r = run("stat " + db);
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("bytes after the checksum"), std::string::npos) << r.err;
  fs::remove(db + "/MANIFEST");
  ASSERT_EQ(run("recover " + db).code, 0);
  std::string nodes_file;
  for (const auto& e : fs::directory_iterator(db)) {
    if (e.path().filename().string().rfind("nodes-", 0) == 0) nodes_file = e.path().filename();
  }
  fs::remove(db + "/" + nodes_file);
  r = run("query " + db + " node 0");
  EXPECT_EQ(r.code, 1);
  EXPECT_EQ(lines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find(nodes_file + " of table 'nodes' is missing"), std::string::npos) << r.err;
}

TEST_F(Robustness, WritersLeaveOtherFilesAlone) {
  const std::string db = mesh_db();
  for (const char* mine : {"notes.txt", "octants-old.bt", "my.bt"})
    std::ofstream(db + "/" + mine) << "mine";
  std::ofstream(db + "/octants-77.bt") << "a leftover";  // a writer's own name pattern
  const CommandRun r = run("balance " + db);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("octants-77.bt"), std::string::npos) << r.err;
  for (const char* mine : {"notes.txt", "octants-old.bt", "my.bt"})
    EXPECT_TRUE(fs::exists(db + "/" + mine));
  EXPECT_FALSE(fs::exists(db + "/octants-77.bt"));
  // A non-empty directory that is not a database is not made one.
  fs::create_directories(dir_.file("home"));
  std::ofstream(dir_.file("home/thesis.tex")) << "mine";
  const CommandRun imp = run("import " + dir_.file("home") + " --octants " + octants_);
  EXPECT_EQ(imp.code, 1);
  EXPECT_NE(imp.err.find("not a weaver database"), std::string::npos) << imp.err;
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_.file("home")), {}), 1);
}

TEST_F(Robustness, MemoryBudgetsAreCheckedNotWrapped) {
  const uint64_t machine = physical_memory();
  ASSERT_GT(machine, 0u);
  const std::string db = mesh_db();
  const std::string too_big = std::to_string(machine / (1 << 20) + 1024) + "M";
  for (const std::string& cmd :
       {"mesh " + dir_.file("m") + " --model halfspace --freq 0.05", "verify " + db,
        "export " + db + " --nodes " + dir_.file("n.csv"), "query " + db + " node 0",
        "balance " + db, "extract " + db, "import " + db + " --octants " + octants_,
        "construct " + db + " --model halfspace"}) {
    for (const std::string& memory :
         {too_big, std::string("9999999999999999999G"), std::string("16E")}) {
      const CommandRun r = run(cmd + " --memory " + memory);
      EXPECT_EQ(r.code, 2) << cmd << " --memory " << memory << ": " << r.err;
      EXPECT_EQ(lines(r.err), 1) << r.err;
    }
  }
  uint64_t v = 0;
  EXPECT_FALSE(parse_bytes("16384P", "--memory", &v).ok());
  EXPECT_FALSE(parse_bytes("17179869184G", "--memory", &v).ok());  // exactly 2^64
  ASSERT_TRUE(parse_bytes("17179869183G", "--memory", &v).ok());
  EXPECT_EQ(v, 17179869183ull << 30);
  ASSERT_TRUE(parse_count("5G", "--max-elements", &v).ok());
  EXPECT_EQ(v, 5000000000ull);
  expect_verifies(db);
}

#ifndef WEAVER_SANITIZED  // the sanitizers reserve more address space than the limit below
TEST_F(Robustness, OutOfMemoryIsOneLineAndExitOne) {
  const std::string db = mesh_db();
  // 200 MB of address space and a 1G budget.  The budget bounds what a
  // command takes; it is not taken up front (buffer pools and sorters grow
  // to it), so a small job runs...
  const std::string limit = "ulimit -v 200000; ";
  for (const std::string& cmd :
       {"verify " + db + " --memory 1G", "query " + db + " node 0 --memory 1G"}) {
    const CommandRun r = run(cmd, limit);
    EXPECT_EQ(r.code, 0) << cmd << ": " << r.err;
  }
  // ...and one that needs more than the limit (a batch of 2M points, as
  // large as the budget allows) ends in one line and exit status 1.
  const CommandRun r = run(
      "query " + db + " locate --points - --memory 1G >/dev/null",
      limit + "awk 'BEGIN { for (i = 0; i < 2000000; i++) print i % 1000, i % 997, i % 991 }' | ");
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_EQ(lines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("out of memory"), std::string::npos) << r.err;
  expect_verifies(db);
}

// A thread the system will not start (here: each thread's stack would be
// the 4 GB the stack limit says, in 3 GB of address space) is one line and
// exit status 1, not an abort; one thread still works, and a writer so
// stopped leaves a database that verifies.
TEST_F(Robustness, AThreadThatCannotStartIsOneLineAndExitOne) {
  const std::string db = mesh_db();
  const std::string limit = "ulimit -s 4000000; ulimit -v 3000000; ";
  for (const std::string& cmd : {"verify " + db, "extract " + db}) {
    const CommandRun r = run(cmd + " --threads 2", limit);
    EXPECT_EQ(r.code, 1) << cmd << ": " << r.err;
    EXPECT_EQ(lines(r.err), 1) << r.err;
    EXPECT_NE(r.err.find("cannot start a thread"), std::string::npos) << r.err;
  }
  EXPECT_EQ(run("verify " + db + " --threads 1", limit).code, 0);
  expect_verifies(db);
}
#endif

TEST_F(Robustness, RunawaySizesAreRefusedBeforeWriting) {
  const std::string db = dir_.file("huge.db");
  for (const char* opts : {"--freq 1e9", "--domain 1e12,1e12,1e12"}) {
    const CommandRun r = run("construct " + db + " --model basin " + opts);
    EXPECT_EQ(r.code, 1) << opts << ": " << r.err;
    EXPECT_NE(r.out.find("estimate"), std::string::npos) << r.out;
    EXPECT_NE(r.err.find("--max-elements"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(db));
  }
  const CommandRun small =
      run("construct " + db + " --model halfspace --freq 0.1 --max-elements 1000");
  EXPECT_EQ(small.code, 1) << small.err;
  const CommandRun ok = run("construct " + db + " --model halfspace --freq 0.1 --max-elements 1M");
  EXPECT_EQ(ok.code, 0) << ok.err;
  const CommandRun mesh = run("mesh " + dir_.file("m") + " --model basin --freq 1e9");
  EXPECT_EQ(mesh.code, 1) << mesh.err;
  EXPECT_FALSE(fs::exists(dir_.file("m")));
}

TEST_F(Robustness, MeshSaysWhichStagesCommittedWhenALaterOneFails) {
  // Count the durable steps of a whole mesh run, then fail one near the end
  // (in extract, after construct has staged its table).
  const std::string args = "mesh DB --model basin --freq 0.05 --domain 20000,20000,10000";
  auto with = [&](const std::string& db) { return std::string(args).replace(5, 2, db); };
  const CommandRun count = run(with(dir_.file("count")), "WEAVER_CRASH_AT=0 ");
  ASSERT_EQ(count.code, 0) << count.err;
  const uint64_t steps = std::stoull(count.err.substr(count.err.find("crash steps: ") + 13));
  // The boundary's steps come last (its commit makes the mesh live).
  const CommandRun bound = run("boundary " + dir_.file("count"), "WEAVER_CRASH_AT=0 ");
  ASSERT_EQ(bound.code, 0) << bound.err;
  const uint64_t boundary_steps =
      std::stoull(bound.err.substr(bound.err.find("crash steps: ") + 13));
  ASSERT_GT(steps, boundary_steps + 6);
  const CommandRun in_boundary =
      run(with(dir_.file("in-boundary")), "WEAVER_FAIL_AT=" + std::to_string(steps - 1) + " ");
  EXPECT_EQ(in_boundary.code, 1);
  EXPECT_NE(in_boundary.err.find("boundary failed"), std::string::npos) << in_boundary.err;
  EXPECT_NE(in_boundary.err.find("nothing committed: the database is as it was"), std::string::npos)
      << in_boundary.err;
  // The last steps of extract lie just before the boundary's (a step or
  // two either way: find one that fails in extract).
  CommandRun late;
  for (uint64_t back = 1; back <= 12; ++back) {
    std::filesystem::remove_all(dir_.file("late"));
    late = run(with(dir_.file("late")),
               "WEAVER_FAIL_AT=" + std::to_string(steps - boundary_steps - back) + " ");
    if (late.err.find("extract failed") != std::string::npos) break;
  }
  EXPECT_EQ(late.code, 1);
  EXPECT_EQ(lines(late.err), 1) << late.err;
  EXPECT_NE(late.err.find("extract failed"), std::string::npos) << late.err;
  // weaver mesh commits once: nothing of the new mesh is left.
  EXPECT_NE(late.err.find("nothing committed: the database is as it was"), std::string::npos)
      << late.err;
  EXPECT_EQ(testing::slurp(dir_.file("late") + "/MANIFEST").find("octants"), std::string::npos);
  expect_verifies(dir_.file("late"));

  // With --unbalanced each stage commits: a failure in balance (a step past
  // construct's own, counted alone) leaves construct's committed table.
  const std::string construct =
      "construct DB --unbalanced --model basin --freq 0.05 --domain 20000,20000,10000";
  const CommandRun alone =
      run(std::string(construct).replace(10, 2, dir_.file("alone")), "WEAVER_CRASH_AT=0 ");
  ASSERT_EQ(alone.code, 0) << alone.err;
  const uint64_t construct_steps =
      std::stoull(alone.err.substr(alone.err.find("crash steps: ") + 13));
  const CommandRun balance = run("balance " + dir_.file("alone"), "WEAVER_CRASH_AT=0 ");
  ASSERT_EQ(balance.code, 0) << balance.err;
  const uint64_t balance_steps =
      std::stoull(balance.err.substr(balance.err.find("crash steps: ") + 13));
  ASSERT_GT(balance_steps, 2u);
  const CommandRun mid =
      run(with(dir_.file("mid")) + " --unbalanced",
          "WEAVER_FAIL_AT=" + std::to_string(construct_steps + balance_steps / 2) + " ");
  EXPECT_EQ(mid.code, 1);
  EXPECT_EQ(lines(mid.err), 1) << mid.err;
  EXPECT_NE(mid.err.find("balance failed"), std::string::npos) << mid.err;
  EXPECT_NE(mid.err.find("construct committed the octant table"), std::string::npos) << mid.err;
  const std::string manifest = testing::slurp(dir_.file("mid") + "/MANIFEST");
  EXPECT_NE(manifest.find("octants"), std::string::npos) << manifest;
  EXPECT_EQ(manifest.find("nodes"), std::string::npos) << manifest;
  // The committed table is construct's, whole: its pages and keys check.
  const CommandRun v = run("verify " + dir_.file("mid") + " --storage-only");
  EXPECT_EQ(v.code, 0) << v.out << v.err;
}

TEST_F(Robustness, SmallProbes) {
  // A directory as --octants.
  CommandRun r = run("import " + dir_.file("db") + " --octants " + dir_.path());
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("is a directory"), std::string::npos) << r.err;
  // Binary garbage is escaped, never echoed raw.
  std::ofstream(dir_.file("bin.txt"), std::ios::binary)
      << std::string("\x1b[2J\x07\x01\xff 1 2 3\n", 13);
  r = run("import " + dir_.file("db") + " --octants " + dir_.file("bin.txt"));
  EXPECT_EQ(r.code, 1);
  EXPECT_EQ(lines(r.err), 1) << r.err;
  for (char c : r.err) EXPECT_TRUE(c == '\n' || (c >= 0x20 && c < 0x7f)) << int(c);
  EXPECT_NE(r.err.find("\\x1b"), std::string::npos) << r.err;
  // Invalid option values are usage errors (2) everywhere.
  for (const char* bad :
       {"construct D --model basin --freq 0", "construct D --model basin --freq -1",
        "mesh D --model basin --freq 0", "construct D --model lava",
        "construct D --model basin --min-level 9 --max-level 3",
        "generate F --kind sphere --level 9 --max-level 3", "extract D --threads 0",
        "import D --octants O --tick -1", "balance D --memory 10",
        "import D --octants O --octants O"}) {
    std::string args = bad;
    if (args.find(" D") != std::string::npos)
      args.replace(args.find(" D"), 2, " " + dir_.file("d"));
    while (args.find(" O") != std::string::npos) args.replace(args.find(" O"), 2, " " + octants_);
    if (args.find(" F") != std::string::npos)
      args.replace(args.find(" F"), 2, " " + dir_.file("f"));
    r = run(args);
    EXPECT_EQ(r.code, 2) << bad << ": " << r.err;
    EXPECT_EQ(lines(r.err), 1) << bad << ": " << r.err;
  }
  // A point past the root is outside the domain, not a usage error.
  const std::string db = mesh_db();
  r = run("query " + db + " locate 2000000 5 5");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("outside the domain"), std::string::npos) << r.out;
  r = run("query " + db + " node-at 1048577 0 0");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("no node"), std::string::npos) << r.out;
  // extract and mesh agree on the default thread count: the cores.
  for (const char* command : {"extract", "mesh"}) {
    std::string help = run(std::string(command) + " --help").out;
    help.erase(std::remove(help.begin(), help.end(), '\n'), help.end());
    help.erase(
        std::unique(help.begin(), help.end(), [](char a, char b) { return a == ' ' && b == ' '; }),
        help.end());
    EXPECT_NE(help.find("(default: the number of cores"), std::string::npos) << command;
  }
}

}  // namespace
}  // namespace weaver
