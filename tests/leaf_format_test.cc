// Tables written before the row dictionary (leaf format 1: payloads always
// column-wise) still read, record for record, beside the same mesh written
// now (format 2, whose octant pages store the repeated materials as row
// dictionaries); `weaver verify` passes on both.  The fixture is a mesh the
// previous build wrote (tests/data/format1/README.md says how).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <string>
#include <vector>

#include "balance/balance.h"
#include "construct/construct.h"
#include "db/database.h"
#include "db/node_table.h"
#include "db/octant_table.h"
#include "extract/extract.h"
#include "partition/partition.h"
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

// The fixture is read, never written.  On a copy, extract (a new node
// table, in leaf format 2, beside format 1's octants) and partition leave a
// mixed database that verifies and holds the same keys and payloads; then
// balance (which rewrites the octant table, in format 2) leaves one that
// verifies too; and the fixture's bytes are as they were.
TEST(LeafFormat, WritersOverAFormatOneDatabaseLeaveAMixedOneThatVerifies) {
  testing::TempDir dir;
  const std::string fixture = std::string(WEAVER_SOURCE_DIR) + "/tests/data/format1/basin.db";
  const auto bytes_of = [](const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  std::map<std::string, std::string> fixture_bytes;
  for (const auto& e : std::filesystem::directory_iterator(fixture)) {
    fixture_bytes[e.path().string()] = bytes_of(e.path().string());
  }
  const auto verifies = [](const std::string& db) {
    VerifyReport report;
    ASSERT_OK(verify_database(db, VerifyOptions{}, &report));
    EXPECT_TRUE(report.ok()) << (report.problems.empty() ? "" : report.problems[0]);
  };
  const std::string db = dir.file("format1");
  std::filesystem::copy(fixture, db);
  const Records octants = read_table(db, kOctantTable), nodes = read_table(db, kNodeTable);
  ASSERT_EQ(octants.leaf_format, 1);
  ExtractResult er;
  ASSERT_OK(extract_mesh(db, ExtractOptions{}, &er));
  PartitionOptions po;
  po.parts = 3;
  PartitionReport pr;
  ASSERT_OK(partition_mesh(db, po, &pr));
  const Records mixed_octants = read_table(db, kOctantTable),
                mixed_nodes = read_table(db, kNodeTable);
  EXPECT_EQ(mixed_octants.leaf_format, 1);  // read, not rewritten
  EXPECT_EQ(mixed_nodes.leaf_format, 2);    // written anew by extract
  EXPECT_EQ(mixed_nodes.keys, nodes.keys);
  EXPECT_TRUE(mixed_nodes.payloads == nodes.payloads);
  ASSERT_NO_FATAL_FAILURE(verifies(db));
  BalanceResult br;
  ASSERT_OK(balance_octree(db, BalanceOptions{}, &br));
  const Records balanced = read_table(db, kOctantTable);
  EXPECT_EQ(balanced.leaf_format, 2);
  EXPECT_EQ(balanced.keys, octants.keys);  // it was balanced already
  EXPECT_TRUE(balanced.payloads == octants.payloads);
  ASSERT_NO_FATAL_FAILURE(verifies(db));
  for (const auto& [path, bytes] : fixture_bytes) {
    EXPECT_TRUE(bytes_of(path) == bytes) << path << " changed";
  }
}

}  // namespace
}  // namespace weaver
