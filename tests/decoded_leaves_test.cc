// Cursors over two handles of one packed table, on two threads, keeping
// their decoded leaves in one DecodedLeaves (a budget of a few leaves, so
// that leaves are evicted while the other thread reads them), read what the
// table holds; and the store decodes each leaf once where it keeps them all.
#include "storage/decoded_leaves.h"

#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <thread>

#include "storage/btree.h"
#include "storage/btree_cursor.h"
#include "storage/file.h"
#include "test_util.h"

namespace weaver {
namespace {

struct Table {
  std::vector<uint64_t> keys;
  std::vector<uint32_t> values;  // the payload of key i
};

Table write_table(const std::string& path) {
  Table t;
  std::mt19937_64 rng(11);
  for (uint64_t k = 0, i = 0; i < 300000; ++i) {
    t.keys.push_back(k += 1 + rng() % 700);
    t.values.push_back(static_cast<uint32_t>(rng()));
  }
  std::unique_ptr<File> f;
  EXPECT_OK(open_posix_file(path, OpenMode::kCreateTruncate, &f));
  TableOptions o;
  std::string error;
  o.schema = *RecordSchema::parse("v:u32", &error);
  o.packed = true;
  std::unique_ptr<BTree> tree;
  EXPECT_OK(BTree::create(std::move(f), o, 1 << 20, &tree));
  EXPECT_OK(tree->append_batch(t.keys.data(), reinterpret_cast<const std::byte*>(t.values.data()),
                               t.keys.size()));
  EXPECT_OK(tree->commit());
  return t;
}

std::unique_ptr<BTree> open_table(const std::string& path) {
  std::unique_ptr<File> f;
  EXPECT_OK(open_posix_file(path, OpenMode::kReadOnly, &f));
  std::unique_ptr<BTree> tree;
  EXPECT_OK(BTree::open(std::move(f), 1 << 20, &tree));
  return tree;
}

// Scans of random ranges from random seeks; the first mismatch, or "".
std::string scan_and_compare(BTree& tree, DecodedLeaves& leaves, const Table& t, uint64_t seed) {
  std::mt19937_64 rng(seed);
  BTreeCursor c;
  c.keep_decoded(&leaves);
  for (int n = 0; n < 300; ++n) {
    const size_t from = rng() % t.keys.size();
    // Its key, or the first key past the one before it.
    const uint64_t at = rng() % 2 == 0 || from == 0 ? t.keys[from] : t.keys[from - 1] + 1;
    if (!tree.seek_cursor(at, &c).ok()) return "seek failed";
    for (size_t i = from, s = rng() % 3000; s > 0 && i < t.keys.size(); --s, ++i) {
      uint32_t v = 0;
      if (!c.valid()) return "ended early";
      std::memcpy(&v, c.payload(), 4);
      if (c.key() != t.keys[i] || v != t.values[i]) return "record " + std::to_string(i);
      if (!c.next().ok()) return "next failed";
    }
  }
  return "";
}

TEST(DecodedLeaves, CursorsOnTwoThreadsShareLeavesAndReadTheTable) {
  testing::TempDir dir;
  const Table t = write_table(dir.file("t"));
  auto a = open_table(dir.file("t")), b = open_table(dir.file("t"));
  for (size_t budget : {size_t{1}, size_t{200} << 10, size_t{64} << 20}) {
    DecodedLeaves leaves(budget);
    std::string got_a, got_b;
    std::thread other([&] { got_b = scan_and_compare(*b, leaves, t, 2); });
    got_a = scan_and_compare(*a, leaves, t, 1);
    other.join();
    EXPECT_EQ(got_a, "") << "budget " << budget;
    EXPECT_EQ(got_b, "") << "budget " << budget;
  }
}

TEST(DecodedLeaves, AStoreThatKeepsEveryLeafDecodesEachOnce) {
  testing::TempDir dir;
  const Table t = write_table(dir.file("t"));
  auto a = open_table(dir.file("t")), b = open_table(dir.file("t"));
  DecodedLeaves leaves(size_t{1} << 30);
  BTreeCursor first, second;
  first.keep_decoded(&leaves);
  second.keep_decoded(&leaves);
  // Every leaf read through a's handle, then found for b's.
  ASSERT_OK(a->seek_cursor(0, &first));
  std::vector<const uint64_t*> decoded;
  for (; first.valid(); first.next()) {
    uint32_t n = 0;
    decoded.push_back(first.keys_in_leaf(&n));
    ASSERT_OK(first.skip(n - 1));
  }
  ASSERT_GT(decoded.size(), 10u);
  ASSERT_OK(b->seek_cursor(0, &second));
  for (const uint64_t* keys : decoded) {
    ASSERT_TRUE(second.valid());
    uint32_t n = 0;
    EXPECT_EQ(second.keys_in_leaf(&n), keys) << "the leaf a's cursor decoded";
    ASSERT_OK(second.skip(n));
  }
  EXPECT_FALSE(second.valid());
}

}  // namespace
}  // namespace weaver
