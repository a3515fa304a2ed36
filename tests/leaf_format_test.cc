// Tables written before the row dictionary (leaf format 1: payloads always
// column-wise) still read, record for record, beside the same mesh written
// now (format 2, whose octant pages store the repeated materials as row
// dictionaries); `weaver verify` passes on both.  The fixture is a mesh the
// previous build wrote (tests/data/format1/README.md says how).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "construct/construct.h"
#include "db/database.h"
#include "db/node_table.h"
#include "db/octant_table.h"
#include "extract/extract.h"
#include "storage/btree.h"
#include "test_util.h"
#include "verify/verify.h"

namespace weaver {
namespace {

struct Records {
  std::vector<uint64_t> keys;
  std::vector<std::byte> payloads;
  int leaf_format = -1;  // byte 25 of the file header
  uint64_t file_bytes = 0;
};

Records read_table(const std::string& db_dir, const std::string& name) {
  Records r;
  std::unique_ptr<Database> db;
  EXPECT_TRUE(Database::open(db_dir, Database::Mode::kRead, false, &db).ok());
  std::unique_ptr<BTree> t;
  EXPECT_TRUE(db->open_table(name, 1 << 20, &t).ok());
  BTreeCursor c;
  EXPECT_TRUE(t->seek_cursor(0, &c).ok());
  while (c.valid()) {
    r.keys.push_back(c.key());
    r.payloads.insert(r.payloads.end(), c.payload(), c.payload() + t->payload_size());
    EXPECT_TRUE(c.next().ok());
  }
  std::ifstream in(db->table_path(name), std::ios::binary);
  in.seekg(25);
  r.leaf_format = in.get();
  r.file_bytes = std::filesystem::file_size(db->table_path(name));
  return r;
}

TEST(LeafFormat, TablesOfTheColumnOnlyFormatStillRead) {
  testing::TempDir dir;
  const std::string old_db = dir.file("format1");
  std::filesystem::copy(std::string(WEAVER_SOURCE_DIR) + "/tests/data/format1/basin.db", old_db);
  ConstructOptions o;
  o.model = "basin";
  o.freq = 0.2;
  o.domain_m = {20000, 20000, 10000};
  ConstructPlan plan;
  ConstructResult cr;
  const std::string new_db = dir.file("format2");
  ASSERT_TRUE(construct_octree(new_db, o, &plan, &cr).ok());
  ExtractResult er;
  ASSERT_TRUE(extract_mesh(new_db, ExtractOptions{}, &er).ok());
  for (const char* table : {kOctantTable, kNodeTable}) {
    SCOPED_TRACE(table);
    const Records before = read_table(old_db, table), now = read_table(new_db, table);
    EXPECT_EQ(before.leaf_format, 1);
    EXPECT_EQ(now.leaf_format, 2);
    ASSERT_GT(before.keys.size(), 5000u);
    EXPECT_EQ(before.keys, now.keys);
    EXPECT_TRUE(before.payloads == now.payloads);
    if (std::string(table) == kOctantTable) {
      EXPECT_LT(2 * now.file_bytes, before.file_bytes) << "materials as row dictionaries";
    }
  }
  for (const std::string& db : {old_db, new_db}) {
    VerifyReport report;
    ASSERT_TRUE(verify_database(db, VerifyOptions{}, &report).ok());
    EXPECT_TRUE(report.ok()) << db << ": " << (report.problems.empty() ? "" : report.problems[0]);
  }
}

}  // namespace
}  // namespace weaver
