#include "db/database.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "test_util.h"

namespace weaver {
namespace {

class DatabaseTest : public ::testing::Test {
 protected:
  std::string db() const { return dir_.file("db"); }
  void make_table(const std::string& name, uint64_t n) {
    std::unique_ptr<Database> d;
    ASSERT_OK(Database::open(db(), Database::Mode::kWrite, true, &d));
    std::unique_ptr<BTree> t;
    std::string file;
    ASSERT_OK(d->create_table(name, TableOptions{}, 1 << 20, &t, &file));
    for (uint64_t i = 0; i < n; ++i) ASSERT_OK(t->append(i, nullptr));
    ASSERT_OK(t->commit());
    ASSERT_OK(d->commit({{name, file}}));
  }
  testing::TempDir dir_;
};

TEST_F(DatabaseTest, CommitReplacesTablesAndRemovesOldFiles) {
  make_table("octants", 10);
  const std::string first = std::filesystem::path([&] {
                              std::unique_ptr<Database> d;
                              EXPECT_OK(Database::open(db(), Database::Mode::kRead, false, &d));
                              return d->table_path("octants");
                            }())
                                .filename();
  make_table("octants", 20);
  std::unique_ptr<Database> d;
  ASSERT_OK(Database::open(db(), Database::Mode::kRead, false, &d));
  std::unique_ptr<BTree> t;
  ASSERT_OK(d->open_table("octants", 1 << 20, &t));
  EXPECT_EQ(t->size(), 20u);
  EXPECT_FALSE(std::filesystem::exists(dir_.file("db/" + first)));
}

// A staged table (Database::stage) is the writer's own until its next
// commit makes it live with that commit's tables; readers see the old one
// meanwhile, and a writer that closes without committing deletes it.
TEST_F(DatabaseTest, StagedTablesGoLiveWithTheNextCommitOrNotAtAll) {
  make_table("octants", 10);
  make_table("nodes", 11);
  auto records = [&](Database& d, const char* name) {
    std::unique_ptr<BTree> t;
    EXPECT_OK(d.open_table(name, 1 << 20, &t));
    return t == nullptr ? uint64_t{0} : t->size();
  };
  auto stage_octants = [&](Database& w, uint64_t n, std::string* file) {
    std::unique_ptr<BTree> t;
    ASSERT_OK(w.create_table("octants", TableOptions{}, 1 << 20, &t, file));
    for (uint64_t i = 0; i < n; ++i) ASSERT_OK(t->append(i, nullptr));
    ASSERT_OK(w.stage("octants", *file, t, Status::Ok()));
  };
  std::string staged;
  {
    std::unique_ptr<Database> w;
    ASSERT_OK(Database::open(db(), Database::Mode::kWrite, false, &w));
    stage_octants(*w, 30, &staged);
    EXPECT_EQ(records(*w, "octants"), 30u);  // the writer reads what it staged
    std::unique_ptr<Database> r;
    ASSERT_OK(Database::open(db(), Database::Mode::kRead, false, &r));
    EXPECT_EQ(records(*r, "octants"), 10u);  // readers see the live table
  }                                          // closed without a commit
  EXPECT_FALSE(std::filesystem::exists(dir_.file("db/" + staged)));
  std::unique_ptr<Database> r;
  ASSERT_OK(Database::open(db(), Database::Mode::kRead, false, &r));
  EXPECT_EQ(records(*r, "octants"), 10u);
  EXPECT_EQ(records(*r, "nodes"), 11u);
  r.reset();
  {
    std::unique_ptr<Database> w;
    ASSERT_OK(Database::open(db(), Database::Mode::kWrite, false, &w));
    stage_octants(*w, 40, &staged);
    std::unique_ptr<BTree> nodes;
    std::string file;
    ASSERT_OK(w->create_table("nodes", TableOptions{}, 1 << 20, &nodes, &file));
    for (uint64_t i = 0; i < 41; ++i) ASSERT_OK(nodes->append(i, nullptr));
    ASSERT_OK(w->publish("nodes", file, nodes, Status::Ok()));
  }
  ASSERT_OK(Database::open(db(), Database::Mode::kRead, false, &r));
  EXPECT_EQ(records(*r, "octants"), 40u);  // both in one commit, nodes not dropped
  EXPECT_EQ(records(*r, "nodes"), 41u);
  EXPECT_TRUE(std::filesystem::exists(dir_.file("db/" + staged)));
}

TEST_F(DatabaseTest, WriterRemovesLeftoversOfACrashedWriter) {
  make_table("octants", 5);
  std::ofstream(dir_.file("db/octants-99.bt")) << "half written";
  std::ofstream(dir_.file("db/MANIFEST.tmp")) << "half written";
  std::filesystem::create_directories(dir_.file("db/tmp-import-123"));
  std::unique_ptr<Database> d;
  ASSERT_OK(Database::open(db(), Database::Mode::kWrite, false, &d));
  EXPECT_EQ(d->cleaned_leftovers().size(), 3u);
  EXPECT_FALSE(std::filesystem::exists(dir_.file("db/octants-99.bt")));
  std::unique_ptr<BTree> t;
  ASSERT_OK(d->open_table("octants", 1 << 20, &t));
  EXPECT_EQ(t->size(), 5u);
}

TEST_F(DatabaseTest, CorruptManifestIsReported) {
  make_table("octants", 5);
  {
    std::fstream f(dir_.file("db/MANIFEST"), std::ios::in | std::ios::out);
    f.seekp(20);
    f.put('#');
  }
  std::unique_ptr<Database> d;
  const Status st = Database::open(db(), Database::Mode::kRead, false, &d);
  ASSERT_TRUE(st.is_corruption()) << st.to_string();
  EXPECT_NE(st.message().find("MANIFEST"), std::string::npos);
}

TEST_F(DatabaseTest, MissingDatabaseAndMissingTableAreNotFound) {
  std::unique_ptr<Database> d;
  EXPECT_TRUE(Database::open(db(), Database::Mode::kRead, false, &d).is_not_found());
  make_table("octants", 1);
  ASSERT_OK(Database::open(db(), Database::Mode::kRead, false, &d));
  std::unique_ptr<BTree> t;
  EXPECT_TRUE(d->open_table("nodes", 1 << 20, &t).is_not_found());
}

TEST_F(DatabaseTest, OneWriterAtATimeReadersAlways) {
  make_table("octants", 1);
  std::unique_ptr<Database> w1, w2, r;
  ASSERT_OK(Database::open(db(), Database::Mode::kWrite, false, &w1));
  EXPECT_TRUE(Database::open(db(), Database::Mode::kWrite, false, &w2).is_busy());
  ASSERT_OK(Database::open(db(), Database::Mode::kRead, false, &r));
  w1.reset();
  ASSERT_OK(Database::open(db(), Database::Mode::kWrite, false, &w2));
}

}  // namespace
}  // namespace weaver
