// No writer puts its output into a database: every command that writes a
// file the user names refuses, with one line and exit status 2, a path
// inside a database directory and a path that is a database, and the
// database is byte for byte what it was.
#include <gtest/gtest.h>

#include <filesystem>
#include <map>

#include "cli_run.h"
#include "db/output_path.h"

namespace weaver {
namespace {

namespace fs = std::filesystem;
using testing::CommandRun;
using testing::run;

// Every file under dir (LOCK aside: a reader never writes it, a writer's
// flock leaves it empty) with its bytes.
std::map<std::string, std::string> contents(const std::string& dir) {
  std::map<std::string, std::string> out;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (e.is_regular_file()) out[fs::relative(e.path(), dir).string()] = testing::slurp(e.path());
  }
  return out;
}

class OutputGuard : public ::testing::Test {
 protected:
  void SetUp() override {
    db_ = dir_.file("basin.db");
    const CommandRun m = run("mesh " + db_ + " --model basin --freq 0.05 --quiet");
    ASSERT_EQ(m.code, 0) << m.err;
    fs::create_directory(dir_.file("out"));
    fs::create_directory_symlink(db_, dir_.file("out/link"));
    before_ = contents(db_);
    ASSERT_GE(before_.size(), 3u);  // MANIFEST and the two tables
  }

  // Paths that land in the database, however they are spelt.
  std::vector<std::string> bad_paths(const std::string& name) const {
    return {db_ + "/MANIFEST",
            db_ + "/octants-1.bt",
            db_ + "/" + name,
            db_ + "/new/" + name,
            dir_.file("out/../basin.db/" + name),
            dir_.file("out/link/" + name),
            db_};
  }

  void expect_refused(const std::string& command, const std::string& args) {
    const CommandRun r = run(command + " " + args);
    EXPECT_EQ(r.code, 2) << command << " " << args << "\n" << r.err;
    EXPECT_EQ(testing::lines(r.err), 1) << r.err;
    EXPECT_NE(r.err.find(" database"), std::string::npos) << r.err;
    EXPECT_TRUE(contents(db_) == before_) << command << " " << args << " changed the database";
    EXPECT_FALSE(fs::exists(db_ + "/new")) << args;
  }

  testing::TempDir dir_;
  std::string db_;
  std::map<std::string, std::string> before_;
};

TEST_F(OutputGuard, EveryExportFormatRefusesToWriteIntoADatabase) {
  const std::pair<const char*, const char*> formats[] = {
      {"vtu", "m.vtu"},         {"pvtu", "m.pvtu"}, {"msh", "m.msh"}, {"metis", "m.graph"},
      {"metis-mesh", "m.mesh"}, {"raw", "raw"},     {"csv", "csv"}};
  for (const auto& [format, name] : formats) {
    for (const std::string& path : bad_paths(name)) {
      expect_refused("export", db_ + " --format " + format + " --out '" + path + "'");
    }
  }
  expect_refused("export", db_ + " --format pvtu --parts 2 --out '" + db_ + ".pvtu'");
  for (const std::string& path : bad_paths("n.csv")) {
    expect_refused("export", db_ + " --nodes '" + path + "'");
    expect_refused("export", db_ + " --elements '" + path + "'");
  }
  // Beside the database, the same commands write.
  const CommandRun ok = run("export " + db_ + " --format vtu --out " + dir_.file("out/m.vtu"));
  EXPECT_EQ(ok.code, 0) << ok.err;
  EXPECT_TRUE(fs::exists(dir_.file("out/m.vtu")));
}

TEST_F(OutputGuard, SliceAndGenerateRefuseToWriteIntoADatabase) {
  for (const std::string& path : bad_paths("s.png")) {
    if (path != db_) expect_refused("slice", db_ + " --at 1000 --out '" + path + "'");
  }
  for (const std::string& path : bad_paths("o.txt")) expect_refused("generate", "'" + path + "'");
  const CommandRun ok = run("slice " + db_ + " --at 1000 --out " + dir_.file("out/s.png"));
  EXPECT_EQ(ok.code, 0) << ok.err;
}

TEST_F(OutputGuard, MeshAndModelImportRefuseADatabaseOfTheOtherKind) {
  const std::string layers = dir_.file("layers.txt");
  std::ofstream(layers) << "0 1500 500 1800\n1000 4000 2300 2500\n";
  expect_refused("model", "import " + db_ + " --from layers:" + layers + " --root-edge 100000");
  const std::string model = dir_.file("model.db");
  const CommandRun m =
      run("model import " + model + " --from layers:" + layers + " --root-edge 100000");
  ASSERT_EQ(m.code, 0) << m.err;
  const auto model_before = contents(model);
  const CommandRun r = run("mesh " + model + " --model basin --freq 0.05 --quiet");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("is a model database"), std::string::npos) << r.err;
  EXPECT_TRUE(contents(model) == model_before);
  // An empty directory takes either kind; the mesh reads the model database.
  fs::create_directory(dir_.file("empty.db"));
  const CommandRun fresh =
      run("mesh " + dir_.file("empty.db") + " --model db:" + model + " --freq 0.05 --quiet");
  EXPECT_EQ(fresh.code, 0) << fresh.err;
}

TEST(OutputPath, RefusesDatabasesAndTheirInsidesOnly) {
  testing::TempDir dir;
  fs::create_directories(dir.file("db"));
  std::ofstream(dir.file("db/MANIFEST")) << "weaver-db 1\n";
  fs::create_directories(dir.file("tables"));
  std::ofstream(dir.file("tables/octants-3.bt")) << "x";
  fs::create_directories(dir.file("project"));
  std::ofstream(dir.file("project/MANIFEST")) << "not a weaver manifest\n";
  EXPECT_TRUE(check_output_path(dir.file("db")).is_invalid_argument());
  EXPECT_TRUE(check_output_path(dir.file("db/x.vtu")).is_invalid_argument());
  EXPECT_TRUE(check_output_path(dir.file("db/a/b/c.vtu")).is_invalid_argument());
  EXPECT_TRUE(check_output_path(dir.file("tables/x.vtu")).is_invalid_argument());
  EXPECT_TRUE(check_output_path(dir.file("project/x.vtu")).ok());
  EXPECT_TRUE(check_output_path(dir.file("x.vtu")).ok());
  EXPECT_TRUE(check_output_path(dir.file("new/x.vtu")).ok());
  EXPECT_FALSE(fs::exists(dir.file("new")));
}

}  // namespace
}  // namespace weaver
