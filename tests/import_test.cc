#include "import/import.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "db/database.h"
#include "gen/octree_gen.h"
#include "import/octant_text.h"
#include "sample_octrees.h"
#include "test_util.h"

namespace weaver {
namespace {

class ImportTest : public ::testing::Test {
 protected:
  std::string write_text(const std::string& body) {
    const std::string path = dir_.file("in-" + std::to_string(files_++) + ".txt");
    std::ofstream(path) << body;
    return path;
  }
  Status run(const std::string& text_path, uint64_t memory = 64 << 20) {
    ImportOptions o;
    o.memory = MemoryBudget(memory);
    return import_octants(db_path(), text_path, o, &result_);
  }
  std::string db_path() const { return dir_.file("db"); }
  std::vector<uint64_t> table_keys() { return testing::octant_table_keys(db_path()); }
  std::vector<std::string> db_files() const {
    std::vector<std::string> names;
    for (auto& e : std::filesystem::directory_iterator(db_path())) {
      names.push_back(e.path().filename().string());
    }
    std::sort(names.begin(), names.end());
    return names;
  }
  // Expects an InvalidArgument naming `line` of `path` and containing `words`.
  void expect_rejected(const std::string& body, int line, const std::string& words) {
    const std::string path = write_text(body);
    const Status st = run(path);
    ASSERT_TRUE(st.is_invalid_argument()) << st.to_string();
    EXPECT_NE(st.message().find(path + ":" + std::to_string(line) + ":"), std::string::npos)
        << st.message();
    EXPECT_NE(st.message().find(words), std::string::npos) << st.message();
  }

  testing::TempDir dir_;
  int files_ = 0;
  ImportResult result_;
};

TEST_F(ImportTest, AcceptsAnyOrderCommentsBlankLinesAndCrlf) {
  const std::string path = write_text(
      "# a comment\n\n524288 0 0 1\r\n0 0 0 1\n  \t\n0 524288 0 1\n524288 524288 0 1\n"
      "0 0 524288 1\n524288 0 524288 1\n0 524288 524288 1\n524288 524288 524288 1");
  ASSERT_OK(run(path));
  EXPECT_EQ(result_.octants, 8u);
  const auto keys = table_keys();
  ASSERT_EQ(keys.size(), 8u);
  for (int k = 0; k < 8; ++k) EXPECT_EQ(keys[k], octant_key(octant_child(octant_root(), k)));
}

TEST_F(ImportTest, RejectsMalformedLines) {
  expect_rejected("0 0 0 1\n0 0 1\n", 2, "expected 4 integers");
  expect_rejected("0 0 0 1 7\n", 1, "found more");
  expect_rejected("0 0 zero 1\n", 1, "expected 4 integers");
  expect_rejected("0 0 0 1.5\n", 1, "expected 4 integers");
}

TEST_F(ImportTest, RejectsOutOfRangeAndMisaligned) {
  expect_rejected("0 0 0 21\n", 1, "level 21 out of range");
  expect_rejected("0 -8 0 3\n", 1, "coordinate -8 out of range");
  expect_rejected("0 0 1048576 20\n", 1, "coordinate 1048576 out of range");
  expect_rejected("# x\n131072 0 65536 3\n", 2, "not a multiple of the edge 131072");
  expect_rejected("0 0 0 1\n99999999999999999999 0 0 1\n", 2, "out of range");
}

TEST_F(ImportTest, RejectsDuplicatesAndOverlapsNamingBothLines) {
  expect_rejected("0 0 0 2\n262144 0 0 2\n0 0 0 2\n", 3, "duplicate of the octant at line 1");
  // A parent after one of its children, and a child after its parent.
  expect_rejected("0 0 0 3\n# gap\n0 0 0 2\n", 3, "overlaps octant (0 0 0 3) at line 1");
  expect_rejected("0 0 0 1\n131072 131072 0 3\n", 2, "octant (131072 131072 0 3) overlaps");
}

TEST_F(ImportTest, RejectsEmptyAndMissingInput) {
  EXPECT_TRUE(run(write_text("# nothing\n\n")).is_invalid_argument());
  EXPECT_TRUE(run(dir_.file("missing.txt")).is_not_found());
}

TEST_F(ImportTest, FailedImportLeavesTheDatabaseAsItWas) {
  // A failed import into a new database leaves no directory behind.
  EXPECT_FALSE(run(write_text("0 0 0 21\n")).ok());
  EXPECT_FALSE(std::filesystem::exists(db_path()));
  // A failed import over a good table keeps the good table, byte for byte.
  ASSERT_OK(run(write_text("0 0 0 0\n")));
  const auto before = table_keys();
  const auto files_before = db_files();
  EXPECT_FALSE(run(write_text("0 0 0 1\n0 0 0 1\n")).ok());
  EXPECT_EQ(table_keys(), before);
  EXPECT_EQ(db_files(), files_before);
}

TEST_F(ImportTest, SecondWriterGetsBusy) {
  ASSERT_OK(run(write_text("0 0 0 0\n")));
  std::unique_ptr<Database> writer;
  ASSERT_OK(Database::open(db_path(), Database::Mode::kWrite, false, &writer));
  const Status st = run(write_text("0 0 0 0\n"));
  EXPECT_TRUE(st.is_busy()) << st.to_string();
  EXPECT_NE(st.message().find("another weaver process"), std::string::npos);
}

TEST_F(ImportTest, OutOfCoreSortMatchesInMemorySort) {
  GenOptions g;
  g.leaves = testing::scaled(300'000, 60'000);
  g.shuffle = true;
  g.seed = 11;
  std::vector<Octant> leaves;
  ASSERT_OK(generate_octree(g, &leaves));
  const std::string path = dir_.file("big.txt");
  ASSERT_OK(write_octant_text(path, leaves, ""));
  ASSERT_OK(run(path, 1 << 20));        // 1 MiB: sorted runs spill to disk
  EXPECT_GE(result_.runs_spilled, 1u);  // the merge path ran
  std::vector<uint64_t> expected;
  for (const Octant& o : leaves) expected.push_back(octant_key(o));
  std::sort(expected.begin(), expected.end());
  EXPECT_EQ(table_keys(), expected);
  for (const std::string& name : db_files()) EXPECT_NE(name.rfind("tmp-", 0), 0u) << name;
}

TEST_F(ImportTest, OutOfCoreSortStillFindsOverlaps) {
  GenOptions g;
  g.leaves = testing::scaled(100'000, 30'000);
  g.shuffle = true;
  std::vector<Octant> leaves;
  ASSERT_OK(generate_octree(g, &leaves));
  leaves.push_back(octant_parent(leaves[leaves.size() / 2]));  // overlaps its children
  const std::string path = dir_.file("bad.txt");
  ASSERT_OK(write_octant_text(path, leaves, ""));
  const Status st = run(path, 1 << 20);
  ASSERT_TRUE(st.is_invalid_argument()) << st.to_string();
  EXPECT_NE(st.message().find("overlaps"), std::string::npos) << st.message();
  EXPECT_FALSE(std::filesystem::exists(db_path()));
}

// Sorted input goes straight into the table: no LSM, nothing spilled, even
// with a budget far below the input.
TEST_F(ImportTest, SortedInputTakesTheAppendPath) {
  GenOptions g;
  g.leaves = testing::scaled(300'000, 60'000);
  std::vector<Octant> leaves;
  ASSERT_OK(generate_octree(g, &leaves));
  std::sort(leaves.begin(), leaves.end(),
            [](const Octant& a, const Octant& b) { return octant_key(a) < octant_key(b); });
  const std::string path = dir_.file("sorted.txt");
  ASSERT_OK(write_octant_text(path, leaves, ""));
  ASSERT_OK(run(path, 1 << 20));
  EXPECT_EQ(result_.runs_spilled, 0u);
  EXPECT_EQ(table_keys().size(), leaves.size());
}

// A repeated octant far apart in shuffled input: the two copies sit in
// different LSM runs, and the merge that meets them names both lines.
TEST_F(ImportTest, OutOfCoreImportNamesBothLinesOfADuplicate) {
  GenOptions g;
  g.leaves = testing::scaled(200'000, 50'000);
  g.shuffle = true;
  g.seed = 5;
  std::vector<Octant> leaves;
  ASSERT_OK(generate_octree(g, &leaves));
  leaves.push_back(leaves[100]);
  const std::string path = dir_.file("dup.txt");
  ASSERT_OK(write_octant_text(path, leaves, ""));
  const Status st = run(path, 1 << 20);
  ASSERT_TRUE(st.is_invalid_argument()) << st.to_string();
  const std::string last = std::to_string(leaves.size());
  EXPECT_NE(st.message().find(path + ":" + last + ": duplicate of the octant at line 101"),
            std::string::npos)
      << st.message();
  EXPECT_FALSE(std::filesystem::exists(db_path()));
}

}  // namespace
}  // namespace weaver
