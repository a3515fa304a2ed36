// The weaver binary as a user runs it: exit codes, one-line errors, output.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>

#include "cli_run.h"

namespace weaver {
namespace {

using testing::CommandRun;
using testing::lines;
using testing::run;

TEST(Cli, EveryCommandHasHelp) {
  const CommandRun top = run("--help");
  EXPECT_EQ(top.code, 0);
  for (const char* cmd :
       {"generate", "import", "construct", "balance", "mesh", "extract", "export", "stat", "query",
        "shell", "slice", "serve", "partition", "verify", "recover", "compact"}) {
    EXPECT_NE(top.out.find(cmd), std::string::npos);
    const CommandRun r = run(std::string(cmd) + " --help");
    EXPECT_EQ(r.code, 0) << cmd;
    EXPECT_NE(r.out.find(std::string("usage: weaver ") + cmd), std::string::npos) << r.out;
  }
}

// `weaver --version`: one line, the project's version (CMakeLists.txt's).
TEST(Cli, VersionIsTheProjectsVersion) {
  const CommandRun r = run("--version");
  EXPECT_EQ(r.code, 0);
  std::ifstream cmake(std::string(WEAVER_SOURCE_DIR) + "/CMakeLists.txt");
  const std::string text(std::istreambuf_iterator<char>(cmake), {});
  const size_t at = text.find("project(weaver VERSION ") + 23;
  ASSERT_GT(at, 23u);
  EXPECT_EQ(r.out, "weaver " + text.substr(at, text.find(' ', at) - at) + "\n");
}

TEST(Cli, UsageErrorsAreOneLineWithStatus2) {
  for (const char* args : {"frobnicate", "import", "import db --octants x --memory lots",
                           "query db locate 1 2", "query db locate 1 2 -3", "stat --bogus db",
                           "generate f --kind fancy", "compact", "compact db --memory lots"}) {
    const CommandRun r = run(args);
    EXPECT_EQ(r.code, 2) << args;
    if (std::string(args) != "frobnicate") {
      EXPECT_EQ(lines(r.err), 1) << args << ": " << r.err;
    }
  }
}

TEST(Cli, ImportStatQueryRoundTrip) {
  testing::TempDir d;
  const CommandRun gen = run("generate " + d.file("o.txt") + " --kind uniform --level 3 --shuffle");
  ASSERT_EQ(gen.code, 0) << gen.err;
  const CommandRun imp =
      run("import " + d.file("db") + " --octants " + d.file("o.txt") + " --tick 2.5");
  ASSERT_EQ(imp.code, 0) << imp.err;
  EXPECT_NE(imp.out.find("imported 512 octants"), std::string::npos) << imp.out;
  const CommandRun stat = run("stat " + d.file("db") + " --json");
  ASSERT_EQ(stat.code, 0);
  EXPECT_NE(stat.out.find("\"records\": 512"), std::string::npos) << stat.out;
  EXPECT_NE(stat.out.find("\"per_level\": {\"3\": 512}"), std::string::npos) << stat.out;
  const CommandRun loc = run("query " + d.file("db") + " locate 131072 0 5");
  ASSERT_EQ(loc.code, 0);
  EXPECT_NE(loc.out.find("element 1: leaf (131072 0 0 3), edge 131072 ticks = 327680 m"),
            std::string::npos)
      << loc.out;
  const CommandRun range = run("query " + d.file("db") + " range 0 0 0 131072 0 0 --json --list");
  ASSERT_EQ(range.code, 0);
  // One JSON document: an array of the leaves, one a line; --format jsonl
  // the same objects without the brackets.
  EXPECT_EQ(lines(range.out), 2) << range.out;
  EXPECT_EQ(range.out.substr(0, 13), "[{\"element\": ") << range.out;
  EXPECT_EQ(range.out.substr(range.out.size() - 3), "}]\n") << range.out;
  EXPECT_NE(range.out.find("{\"element\": 1, \"x\": 131072, \"y\": 0, \"z\": 0, \"level\": 3"),
            std::string::npos)
      << range.out;
  const CommandRun jsonl =
      run("query " + d.file("db") + " range 0 0 0 131072 0 0 --format jsonl --list");
  ASSERT_EQ(jsonl.code, 0);
  EXPECT_EQ(lines(jsonl.out), 2) << jsonl.out;
  EXPECT_EQ(jsonl.out.substr(0, 2), "{\"") << jsonl.out;
  EXPECT_EQ(jsonl.out.find('['), std::string::npos) << jsonl.out;
}

TEST(Cli, DataErrorsAreOneLineWithStatus1) {
  testing::TempDir d;
  std::ofstream(d.file("bad.txt")) << "0 0 0 1\n0 0 0 1\n";
  const CommandRun imp = run("import " + d.file("db") + " --octants " + d.file("bad.txt"));
  EXPECT_EQ(imp.code, 1);
  EXPECT_EQ(lines(imp.err), 1) << imp.err;
  EXPECT_NE(imp.err.find("bad.txt:2: duplicate"), std::string::npos) << imp.err;
  const CommandRun q = run("query " + d.file("nothing") + " locate 1 2 3");
  EXPECT_EQ(q.code, 1);
  EXPECT_EQ(lines(q.err), 1) << q.err;
}

// compact: a database without shards is left as it is; a missing one is a
// one-line error.  (Joining shards is checked in sharded_db_test.cc and,
// under mpirun, tools/check_mpi.sh.)
TEST(Cli, CompactLeavesTablesOfOneFileAlone) {
  testing::TempDir d;
  ASSERT_EQ(run("generate " + d.file("o.txt") + " --kind uniform --level 2").code, 0);
  ASSERT_EQ(run("import " + d.file("db") + " --octants " + d.file("o.txt")).code, 0);
  const std::string before = testing::slurp(d.file("db") + "/MANIFEST");
  const CommandRun c = run("compact " + d.file("db"));
  EXPECT_EQ(c.code, 0) << c.err;
  EXPECT_NE(c.out.find("has no sharded tables"), std::string::npos) << c.out;
  EXPECT_EQ(testing::slurp(d.file("db") + "/MANIFEST"), before);
  const CommandRun missing = run("compact " + d.file("nothing"));
  EXPECT_EQ(missing.code, 1);
  EXPECT_EQ(lines(missing.err), 1) << missing.err;
}

TEST(Cli, MeshRunsThePipelineAndBalanceCheckAgrees) {
  testing::TempDir d;
  const CommandRun mesh = run("mesh " + d.file("db") +
                              " --model loh1 --freq 0.5 --domain 20000,20000,10000 --threads 2");
  ASSERT_EQ(mesh.code, 0) << mesh.err;
  for (const char* word :
       {"construct", "balanced", "extract", "elements", "danglings", "points per wavelength"}) {
    EXPECT_NE(mesh.out.find(word), std::string::npos) << word << "\n" << mesh.out;
  }
  const CommandRun check = run("balance " + d.file("db") + " --check");
  EXPECT_EQ(check.code, 0) << check.err;
  EXPECT_NE(check.out.find("2:1 balanced"), std::string::npos);
  const CommandRun bad = run("construct " + d.file("db2") + " --model lava");
  EXPECT_NE(bad.code, 0);
  EXPECT_EQ(lines(bad.err), 1) << bad.err;
}

// Progress lines (plain, as stderr is a file here; WEAVER_PROGRESS_SECONDS=0
// prints one per report): each stage's percent never goes back and stays
// within 0..100, and --quiet prints nothing on stderr.
TEST(Cli, ProgressLinesPerStageWithHonestPercentsAndQuietSilencesThem) {
  testing::TempDir d;
  const std::string args = " --model basin --freq 0.3 --domain 50000,50000,25000";
  const CommandRun mesh = run("mesh " + d.file("db") + args, "WEAVER_PROGRESS_SECONDS=0 ");
  ASSERT_EQ(mesh.code, 0) << mesh.err;
  std::map<std::string, double> last;
  std::istringstream in(mesh.err);
  std::string line;
  int shown = 0;
  while (std::getline(in, line)) {
    const size_t colon = line.find(": ");
    ASSERT_NE(colon, std::string::npos) << line;
    const std::string stage = line.substr(0, colon);
    // construct balances as it descends: no balance stage.
    ASSERT_TRUE(stage == "construct" || stage == "extract") << line;
    const double percent = std::stod(line.substr(colon + 2));
    EXPECT_GE(percent, last[stage]) << line;
    EXPECT_LE(percent, 100.0) << line;
    EXPECT_NE(line.find("/s"), std::string::npos) << line;
    last[stage] = percent;
    ++shown;
  }
  EXPECT_EQ(last.size(), 2u) << mesh.err;
  EXPECT_GT(shown, 10);
  EXPECT_GT(last["extract"], 50.0);  // extract reports by elements: it reaches near the end
  const CommandRun quiet =
      run("mesh " + d.file("db2") + args + " --quiet", "WEAVER_PROGRESS_SECONDS=0 ");
  ASSERT_EQ(quiet.code, 0) << quiet.err;
  EXPECT_EQ(quiet.err, "");
  // verify's mesh check counts nodes against the node table.
  const CommandRun verify = run("verify " + d.file("db"), "WEAVER_PROGRESS_SECONDS=0 ");
  ASSERT_EQ(verify.code, 0) << verify.err;
  EXPECT_EQ(verify.err.rfind("verify: ", 0), 0u) << verify.err;
  EXPECT_NE(verify.err.find(" nodes "), std::string::npos) << verify.err;
  for (const char* command : {"construct", "balance", "extract", "import", "export", "verify"}) {
    const CommandRun help = run(std::string(command) + " --help");
    EXPECT_NE(help.out.find("--quiet"), std::string::npos) << command;
  }
}

// model import of a grid whose every point differs (32K octants stored, a
// batch of 4096 at a time): a progress line per batch stored, the octants
// never fewer than the line before; none with --quiet.
TEST(Cli, ModelImportShowsProgressAndQuietSilencesIt) {
  testing::TempDir d;
  const std::string grid = d.file("g.grid");
  {
    std::ofstream f(grid, std::ios::binary);
    f << "weaver-grid 1\n32 32 32\n0 0 0\n100 100 100\n";
    for (int i = 0; i < 32 * 32 * 32; ++i) {
      const float v[3] = {3000.0f + i, 1500.0f + i, 2000.0f};
      f.write(reinterpret_cast<const char*>(v), sizeof v);
    }
  }
  const CommandRun import =
      run("model import " + d.file("m.db") + " --from grid:" + grid, "WEAVER_PROGRESS_SECONDS=0 ");
  ASSERT_EQ(import.code, 0) << import.err;
  std::istringstream in(import.err);
  std::string line;
  uint64_t last = 0;
  int shown = 0;
  while (std::getline(in, line)) {
    ASSERT_EQ(line.rfind("model import: ", 0), 0u) << line;
    // The count, its digits grouped by spaces: "model import: 12 288 octants  ...".
    const size_t unit = line.find(" octants");
    ASSERT_NE(unit, std::string::npos) << line;
    std::string digits = line.substr(14, unit - 14);
    digits.erase(std::remove(digits.begin(), digits.end(), ' '), digits.end());
    const uint64_t octants = std::stoull(digits);
    EXPECT_GE(octants, last) << line;
    last = octants;
    ++shown;
  }
  EXPECT_GE(shown, 2) << import.err;
  EXPECT_EQ(last, 32u * 32 * 32) << import.err;  // the last batch: every point stored
  const CommandRun quiet =
      run("model import " + d.file("m2.db") + " --from grid:" + grid + " --quiet",
          "WEAVER_PROGRESS_SECONDS=0 ");
  ASSERT_EQ(quiet.code, 0) << quiet.err;
  EXPECT_EQ(quiet.err, "");
  EXPECT_NE(run("model --help").out.find("--quiet"), std::string::npos);
}

// The same mesh with packed pages (the default) and with --plain: the stat
// says which, the packed tables are smaller, and every exported row is the same.
TEST(Cli, PackedAndPlainTablesHoldTheSameMesh) {
  testing::TempDir d;
  std::string csv[2];
  uint64_t bytes[2] = {0, 0};
  for (const bool plain : {false, true}) {
    const std::string db = d.file(plain ? "plain" : "packed");
    const std::string flag = plain ? " --plain" : "";
    const CommandRun mesh =
        run("mesh " + db + " --model basin --freq 0.1 --domain 40000,40000,20000" + flag);
    ASSERT_EQ(mesh.code, 0) << mesh.err;
    const CommandRun stat = run("stat " + db + " --json");
    ASSERT_EQ(stat.code, 0) << stat.err;
    const std::string want = plain ? "\"packed\": false" : "\"packed\": true";
    EXPECT_EQ(stat.out.find(plain ? "\"packed\": true" : "\"packed\": false"), std::string::npos)
        << stat.out;
    EXPECT_NE(stat.out.find(want), std::string::npos) << stat.out;
    const size_t at = stat.out.find("\"bytes\": ");
    ASSERT_NE(at, std::string::npos);
    bytes[plain] = std::stoull(stat.out.substr(at + 9));
    const CommandRun exp =
        run("export " + db + " --nodes " + db + ".n.csv --elements " + db + ".e.csv");
    ASSERT_EQ(exp.code, 0) << exp.err;
    std::ifstream n(db + ".n.csv"), e(db + ".e.csv");
    csv[plain].assign(std::istreambuf_iterator<char>(n), {});
    csv[plain].append(std::istreambuf_iterator<char>(e), {});
  }
  EXPECT_GT(csv[0].size(), 1000u);
  EXPECT_TRUE(csv[0] == csv[1]) << "packed and plain meshes differ";
  EXPECT_LT(bytes[0] * 2, bytes[1]) << "the first table is not packed smaller";
}

}  // namespace
}  // namespace weaver
