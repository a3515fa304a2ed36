// A table cut into shard files answers, through BTree::open_sharded, as the
// whole table: get, floor, rank, select, leaf_keys and both kinds of cursor,
// checked against a std::map of the same records
// (the slow, obviously correct reference) for cuts of every kind, including
// one-record shards and keys between shards, below and above them all.
#include "storage/shard_set.h"

#include <gtest/gtest.h>

#include <cstring>
#include <map>
#include <random>

#include "test_util.h"

namespace weaver {
namespace {

using testing::TempDir;
using Records = std::map<uint64_t, uint64_t>;  // key -> payload (8 bytes)

std::unique_ptr<BTree> write_shard(const std::string& path, Records::const_iterator from,
                                   Records::const_iterator to, bool packed) {
  TableOptions o;
  o.packed = packed;
  o.key_kind = KeyKind::kNode;
  std::string err;
  o.schema = *RecordSchema::parse("v:u64", &err);
  std::unique_ptr<File> f;
  EXPECT_OK(open_posix_file(path, OpenMode::kCreateTruncate, &f));
  std::unique_ptr<BTree> t;
  EXPECT_OK(BTree::create(std::move(f), o, 1 << 20, &t));
  for (auto it = from; it != to; ++it) {
    EXPECT_OK(t->append(it->first, reinterpret_cast<const std::byte*>(&it->second)));
  }
  EXPECT_OK(t->commit());
  return t;
}

// The records cut at `cuts` (positions, increasing) into shard files.
std::unique_ptr<BTree> cut(const TempDir& dir, const Records& r, std::vector<size_t> cuts,
                           bool packed) {
  std::vector<std::unique_ptr<BTree>> shards;
  cuts.insert(cuts.begin(), 0);
  cuts.push_back(r.size());
  for (size_t s = 0; s + 1 < cuts.size(); ++s) {
    auto from = std::next(r.begin(), long(cuts[s])), to = std::next(r.begin(), long(cuts[s + 1]));
    shards.push_back(write_shard(dir.file("s" + std::to_string(s) + ".bt"), from, to, packed));
  }
  std::unique_ptr<BTree> set;
  EXPECT_OK(BTree::open_sharded(std::move(shards), &set));
  return set;
}

// The records in key order, by rank.
using Flat = std::vector<std::pair<uint64_t, uint64_t>>;

uint64_t rank_of(const Flat& flat, uint64_t k) {
  return uint64_t(std::lower_bound(flat.begin(), flat.end(), std::make_pair(k, uint64_t{0})) -
                  flat.begin());
}

void check_key(BTree& set, const Records& r, const Flat& flat, uint64_t k) {
  uint64_t v = 0, key = 0, rank = 0;
  bool found = false, present = false;
  ASSERT_OK(set.get(k, reinterpret_cast<std::byte*>(&v), &found));
  ASSERT_EQ(found, r.count(k) == 1) << k;
  if (found) {
    ASSERT_EQ(v, r.at(k));
  }
  ASSERT_OK(set.floor(k, &key, reinterpret_cast<std::byte*>(&v), &found));
  auto up = r.upper_bound(k);
  ASSERT_EQ(found, up != r.begin()) << k;
  if (found) {
    ASSERT_EQ(key, std::prev(up)->first);
    ASSERT_EQ(v, std::prev(up)->second);
  }
  ASSERT_OK(set.rank_exact(k, &rank, &present));
  ASSERT_EQ(rank, rank_of(flat, k)) << k;
  ASSERT_EQ(present, r.count(k) == 1);
  std::unique_ptr<Cursor> c;
  ASSERT_OK(set.seek(k, &c));
  BTreeCursor keys;
  ASSERT_OK(set.seek_keys(k, &keys));
  auto it = r.lower_bound(k);
  for (int steps = 0; steps < 40 && it != r.end(); ++steps, ++it) {
    ASSERT_TRUE(c->valid()) << k;
    ASSERT_EQ(c->key(), it->first);
    ASSERT_OK(c->next());
    ASSERT_TRUE(keys.valid()) << k;
    ASSERT_EQ(keys.key(), it->first);
    ASSERT_OK(keys.next());
  }
  if (it == r.end()) {
    ASSERT_FALSE(c->valid());
    ASSERT_FALSE(keys.valid());
  }
  // The leaf where k is or would be: its keys are the records of their ranks.
  std::vector<uint64_t> leaf;
  std::vector<std::byte> vals;
  uint64_t first = 0;
  ASSERT_OK(set.leaf_keys(k, &leaf, &first, &vals));
  ASSERT_FALSE(leaf.empty());
  ASSERT_EQ(vals.size(), leaf.size() * 8);
  ASSERT_LE(first + leaf.size(), flat.size());
  auto at = flat.begin() + long(first);
  for (size_t i = 0; i < leaf.size(); ++i, ++at) {
    ASSERT_EQ(leaf[i], at->first) << k;
    uint64_t v = 0;
    std::memcpy(&v, vals.data() + 8 * i, 8);
    ASSERT_EQ(v, at->second);
  }
  // ... and k's rank lies within it, or just past it.
  const uint64_t k_rank = rank_of(flat, k);
  ASSERT_LE(first, k_rank) << k;
  ASSERT_LE(k_rank, first + leaf.size()) << k;
}

TEST(ShardSet, AnswersAsTheWholeTableForEveryCut) {
  std::mt19937_64 rng(17);
  Records r;
  while (r.size() < 20000) r[rng() % 1000000 * 16] = rng();
  const size_t n = r.size();
  const Flat flat(r.begin(), r.end());
  const std::vector<std::vector<size_t>> cuts = {
      {}, {n / 2}, {1, 2, 3}, {n - 1}, {137, 5000, 5001, 19000}, {n / 4, n / 2, 3 * n / 4}};
  for (bool packed : {false, true}) {
    for (const auto& c : cuts) {
      TempDir dir;
      std::unique_ptr<BTree> set = cut(dir, r, c, packed);
      ASSERT_EQ(set->shard_count(), c.size() + 1);
      ASSERT_OK(set->check_invariants());
      ASSERT_EQ(set->size(), n);
      // Every record by rank, and by a scan from the start.
      std::unique_ptr<Cursor> all;
      ASSERT_OK(set->seek(0, &all));
      uint64_t rank = 0;
      for (const auto& [k, v] : r) {
        uint64_t key = 0, got = 0;
        ASSERT_OK(set->select(rank++, &key, reinterpret_cast<std::byte*>(&got)));
        ASSERT_EQ(key, k);
        ASSERT_EQ(got, v);
        ASSERT_TRUE(all->valid());
        ASSERT_EQ(all->key(), k);
        ASSERT_OK(all->next());
      }
      ASSERT_FALSE(all->valid());
      EXPECT_FALSE(set->select(n, nullptr, nullptr).ok());
      // Keys present, absent, at and around every shard's ends.
      std::vector<uint64_t> keys = {0, 1, ~uint64_t{0}};
      for (size_t p : c) {
        const uint64_t at = flat[p].first;
        keys.insert(keys.end(), {at - 1, at, at + 1});
      }
      for (int i = 0; i < 2000; ++i) keys.push_back(rng() % (1000000 * 16 + 100));
      for (int i = 0; i < 500; ++i) keys.push_back(flat[rng() % n].first);
      for (uint64_t k : keys) check_key(*set, r, flat, k);
      // Writes are refused, naming the way to a table of one file.
      const Status st = set->append(~uint64_t{0}, reinterpret_cast<const std::byte*>(&n));
      ASSERT_FALSE(st.ok());
      EXPECT_NE(st.message().find("weaver compact"), std::string::npos) << st.message();
    }
  }
}

TEST(ShardSet, RefusesShardsOutOfOrderOrEmpty) {
  TempDir dir;
  Records a = {{10, 1}, {20, 2}}, b = {{15, 3}, {30, 4}}, none;
  for (auto [second, why] : {std::pair<const Records*, const char*>{&b, "starts at or before"},
                             std::pair<const Records*, const char*>{&none, "is empty"}}) {
    std::vector<std::unique_ptr<BTree>> shards;
    shards.push_back(write_shard(dir.file("a.bt"), a.begin(), a.end(), false));
    shards.push_back(write_shard(dir.file("b.bt"), second->begin(), second->end(), false));
    std::unique_ptr<ShardSet> set;
    const Status st = ShardSet::make(std::move(shards), &set);
    ASSERT_FALSE(st.ok());
    EXPECT_NE(st.message().find(why), std::string::npos) << st.message();
    EXPECT_NE(st.message().find("shard 1 ("), std::string::npos) << st.message();
  }
}

}  // namespace
}  // namespace weaver
