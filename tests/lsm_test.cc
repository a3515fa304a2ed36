// The LSM store against std::map under random mixes of every operation, with
// a memtable so small that flushes and tiered merges happen all the time; a
// compacted store against a B+tree built by sorted append (byte for byte);
// and commit / reopen / leftover removal.
#include "storage/lsm.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <random>
#include <vector>

#include "test_util.h"

namespace weaver {
namespace {

constexpr uint32_t kPayload = 12;
using Map = std::map<uint64_t, std::vector<std::byte>>;

LsmOptions small_options(uint64_t memtable_bytes) {
  LsmOptions o;
  std::string error;
  o.table.schema = *RecordSchema::parse("a:u32,b:u64", &error);
  o.table.page_size = 256;  // deep runs
  o.table.metadata = "test=1";
  o.memtable_bytes = memtable_bytes;
  o.run_pool_bytes = 16 << 10;
  return o;
}

std::vector<std::byte> payload_for(uint64_t key, uint64_t version) {
  std::vector<std::byte> p(kPayload);
  const uint64_t v = key * 31 + version;
  std::memcpy(p.data(), &v, 8);
  std::memcpy(p.data() + 8, &version, 4);
  return p;
}

// Every read the Store offers, against the model.
void check_reads(LsmTree& t, const Map& m, std::mt19937_64& rng, uint64_t key_range) {
  std::vector<std::byte> buf(kPayload);
  for (int q = 0; q < 200; ++q) {
    const uint64_t k = rng() % key_range;
    bool found = false;
    ASSERT_OK(t.get(k, buf.data(), &found));
    auto it = m.find(k);
    ASSERT_EQ(found, it != m.end()) << "get " << k;
    if (found) {
      ASSERT_EQ(buf, it->second) << "get " << k;
    }
    uint64_t fk = 0;
    ASSERT_OK(t.floor(k, &fk, buf.data(), &found));
    auto ub = m.upper_bound(k);
    ASSERT_EQ(found, ub != m.begin()) << "floor " << k;
    if (found) {
      ASSERT_EQ(fk, std::prev(ub)->first) << "floor " << k;
      ASSERT_EQ(buf, std::prev(ub)->second) << "floor " << k;
    }
  }
  const uint64_t from = rng() % key_range;
  std::unique_ptr<Cursor> c;
  ASSERT_OK(t.seek(from, &c));
  auto it = m.lower_bound(from);
  for (int i = 0; i < 300 && it != m.end(); ++i, ++it) {
    ASSERT_TRUE(c->valid());
    ASSERT_EQ(c->key(), it->first);
    ASSERT_TRUE(std::equal(it->second.begin(), it->second.end(), c->payload()));
    ASSERT_OK(c->next());
  }
  if (it == m.end()) {
    ASSERT_FALSE(c->valid());
  }
  uint64_t r = 0;
  ASSERT_OK(t.rank(from, &r));
  ASSERT_EQ(r, static_cast<uint64_t>(std::distance(m.begin(), m.lower_bound(from))));
  if (!m.empty()) {
    const uint64_t index = rng() % m.size();
    uint64_t key = 0;
    ASSERT_OK(t.select(index, &key, buf.data()));
    ASSERT_EQ(key, std::next(m.begin(), static_cast<long>(index))->first);
  }
  uint64_t n = 0;
  ASSERT_OK(t.count(&n));
  ASSERT_EQ(n, m.size());
  ASSERT_EQ(t.size(), m.size());  // count() made it exact
}

TEST(LsmModel, RandomMixesMatchAMap) {
  for (uint64_t seed = 1; seed <= testing::scaled(6, 2); ++seed) {
    testing::TempDir dir;
    std::unique_ptr<LsmTree> t;
    LsmOptions o = small_options(8 << 10);
    o.table.packed = seed % 4 >= 2;  // runs with packed leaves: seeds 2, 3, 6
    ASSERT_OK(LsmTree::create(dir.file("lsm"), o, &t));
    Map m;
    std::mt19937_64 rng(seed);
    const uint64_t key_range = seed % 2 ? 5000 : 1'000'000'000;
    for (uint64_t op = 0; op < 30000; ++op) {
      const uint64_t k = rng() % key_range;
      const int what = static_cast<int>(rng() % 10);
      if (what < 6) {  // blind put
        m[k] = payload_for(k, op);
        ASSERT_OK(t->put(k, m[k].data(), nullptr));
      } else if (what < 7) {  // put that asks
        bool replaced = false;
        const bool had = m.count(k) != 0;
        m[k] = payload_for(k, op);
        ASSERT_OK(t->put(k, m[k].data(), &replaced));
        ASSERT_EQ(replaced, had);
      } else if (what < 9) {  // erase a present key, or an absent one
        auto it = m.lower_bound(k);
        if (it != m.end() && rng() % 4 != 0) {
          ASSERT_OK(t->erase(it->first));
          m.erase(it);
        } else if (m.count(k) == 0) {
          ASSERT_TRUE(t->erase(k).is_not_found());
        }
      } else if (op % 97 == 0) {
        ASSERT_NO_FATAL_FAILURE(check_reads(*t, m, rng, key_range));
      }
      if (op % 7919 == 0) ASSERT_OK(t->commit());
    }
    EXPECT_GT(t->runs_written(), 20u) << "the memtable should have flushed many times";
    ASSERT_NO_FATAL_FAILURE(check_reads(*t, m, rng, key_range));
    ASSERT_OK(t->compact());
    EXPECT_LE(t->run_count(), 1u);
    EXPECT_TRUE(t->size_exact());
    ASSERT_NO_FATAL_FAILURE(check_reads(*t, m, rng, key_range));
  }
}

TEST(LsmModel, TieredMergesBoundTheRunCount) {
  testing::TempDir dir;
  std::unique_ptr<LsmTree> t;
  ASSERT_OK(LsmTree::create(dir.file("lsm"), small_options(16 << 10), &t));
  std::mt19937_64 rng(3);
  const std::vector<std::byte> p(kPayload);
  size_t most_runs = 0;
  for (int i = 0; i < 200000; ++i) {
    ASSERT_OK(t->put(rng(), p.data(), nullptr));
    most_runs = std::max(most_runs, t->run_count());
  }
  // ~560 flushes: tiers 0..4, at most 3 runs each plus the one being merged.
  EXPECT_LE(most_runs, 3u * 5 + 1);
  EXPECT_GT(t->runs_written(), 500u);
  // Each record rewritten about log4(flushes) ~ 4.6 times, not once per flush.
  EXPECT_LT(t->records_written(), 7u * 200000);
}

std::vector<char> file_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// The design promise: a compacted LSM is what sorted append builds, with
// plain and with packed leaves.
class LsmCompaction : public ::testing::TestWithParam<bool> {};

TEST_P(LsmCompaction, EndsInTheFileASortedAppendBuilds) {
  testing::TempDir dir;
  LsmOptions o = small_options(32 << 10);
  o.table.packed = GetParam();
  std::unique_ptr<LsmTree> t;
  ASSERT_OK(LsmTree::create(dir.file("lsm"), o, &t));
  Map m;
  std::mt19937_64 rng(11);
  for (uint64_t op = 0; op < 60000; ++op) {
    const uint64_t k = rng() % 100000;
    if (op % 5 == 4 && m.count(k) != 0) {
      ASSERT_OK(t->erase(k));
      m.erase(k);
    } else {
      m[k] = payload_for(k, op);
      ASSERT_OK(t->put(k, m[k].data(), nullptr));
    }
  }
  ASSERT_OK(t->compact());
  ASSERT_OK(t->commit());
  ASSERT_EQ(t->run_count(), 1u);
  BTree* run = t->compacted_run();
  ASSERT_NE(run, nullptr);

  std::unique_ptr<File> f;
  ASSERT_OK(open_posix_file(dir.file("appended.bt"), OpenMode::kCreateTruncate, &f));
  std::unique_ptr<BTree> appended;
  ASSERT_OK(BTree::create(std::move(f), o.table, 1 << 20, &appended));
  for (const auto& [k, p] : m) ASSERT_OK(appended->append(k, p.data()));
  ASSERT_OK(appended->commit());
  EXPECT_EQ(run->file_bytes(), appended->file_bytes());
  EXPECT_EQ(t->file_bytes(), appended->file_bytes());
  const auto a = file_bytes(run->file_name()), b = file_bytes(dir.file("appended.bt"));
  EXPECT_EQ(a.size(), b.size());
  EXPECT_TRUE(a == b) << "compacted run and sorted append differ";

  // compact_into writes the same records into a tree of the caller's.
  ASSERT_OK(open_posix_file(dir.file("into.bt"), OpenMode::kCreateTruncate, &f));
  std::unique_ptr<BTree> into;
  ASSERT_OK(BTree::create(std::move(f), o.table, 1 << 20, &into));
  ASSERT_OK(t->compact_into(*into));
  ASSERT_OK(into->commit());
  EXPECT_TRUE(file_bytes(dir.file("into.bt")) == b);
}

INSTANTIATE_TEST_SUITE_P(PlainAndPacked, LsmCompaction, ::testing::Bool(),
                         [](const ::testing::TestParamInfo<bool>& info) {
                           return info.param ? "packed" : "plain";
                         });

TEST(LsmPersistence, ReopensTheCommittedStateAndDropsTheRest) {
  testing::TempDir dir;
  const std::string path = dir.file("lsm");
  Map committed;
  {
    std::unique_ptr<LsmTree> t;
    ASSERT_OK(LsmTree::create(path, small_options(8 << 10), &t));
    for (uint64_t k = 0; k < 20000; ++k) {
      committed[k * 7 % 20011] = payload_for(k, 1);
      ASSERT_OK(t->put(k * 7 % 20011, committed[k * 7 % 20011].data(), nullptr));
    }
    for (uint64_t k = 0; k < 20000; k += 3) {
      ASSERT_OK(t->erase(k * 7 % 20011));
      committed.erase(k * 7 % 20011);
    }
    ASSERT_OK(t->commit());
    // Not committed: more writes, flushes and merges, then the process "dies".
    for (uint64_t k = 0; k < 20000; ++k) ASSERT_OK(t->put(k + 50000, nullptr, nullptr));
    EXPECT_TRUE(LsmTree::create(path, small_options(8 << 10), &t).is_invalid_argument());
  }
  std::unique_ptr<LsmTree> t;
  ASSERT_OK(LsmTree::open(path, small_options(8 << 10), &t));
  EXPECT_EQ(t->options().schema.to_text(), "a:u32,b:u64");
  EXPECT_EQ(t->options().metadata, "test=1");
  std::mt19937_64 rng(5);
  ASSERT_NO_FATAL_FAILURE(check_reads(*t, committed, rng, 80000));
  for (const auto& entry : std::filesystem::directory_iterator(path)) {
    const std::string name = entry.path().filename().string();
    const bool listed = name == "LSM" || (name.rfind("run-", 0) == 0 && t->run_count() > 0);
    EXPECT_TRUE(listed) << name;
  }
  size_t files = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(path)) ++files;
  EXPECT_EQ(files, t->run_count() + 1) << "uncommitted runs must be removed";
}

TEST(LsmPersistence, AppendKeepsKeyOrderAcrossRuns) {
  testing::TempDir dir;
  std::unique_ptr<LsmTree> t;
  ASSERT_OK(LsmTree::create(dir.file("lsm"), small_options(4 << 10), &t));
  for (uint64_t k = 10; k < 5000; k += 2) ASSERT_OK(t->append(k, nullptr));
  EXPECT_TRUE(t->append(4000, nullptr).is_invalid_argument());
  ASSERT_OK(t->erase(4998));
  ASSERT_OK(t->append(4997, nullptr));  // above every live key
  EXPECT_EQ(t->size(), 2495u);
  EXPECT_TRUE(t->size_exact());
}

// The shadow hook sees every entry that hides an older one of its key: over
// the memtable at once, over a run when a merge or a read meets the two.
TEST(LsmShadowHook, ReportsEachHiddenEntryAndCanFailTheOperation) {
  testing::TempDir dir;
  LsmOptions o = small_options(1 << 20);
  std::vector<std::pair<uint64_t, uint64_t>> seen;  // key, older version
  o.on_shadow = [&](uint64_t key, const std::byte* newer, const std::byte* older) {
    uint64_t v = 0;
    if (older != nullptr) std::memcpy(&v, older + 8, 4);
    seen.emplace_back(key, v);
    if (newer != nullptr) std::memcpy(&v, newer + 8, 4);
    return v == 99 ? Status::InvalidArgument("no version 99") : Status::Ok();
  };
  std::unique_ptr<LsmTree> t;
  ASSERT_OK(LsmTree::create(dir.file("lsm"), o, &t));
  ASSERT_OK(t->put(5, payload_for(5, 1).data(), nullptr));
  ASSERT_OK(t->put(5, payload_for(5, 2).data(), nullptr));  // over the memtable
  ASSERT_EQ(seen.size(), 1u);
  EXPECT_EQ(seen[0], std::make_pair(uint64_t{5}, uint64_t{1}));
  ASSERT_OK(t->commit());                                   // 5 moves to a run
  ASSERT_OK(t->put(5, payload_for(5, 3).data(), nullptr));  // no memtable entry to hide
  ASSERT_EQ(seen.size(), 1u);
  ASSERT_OK(t->compact());  // the merge meets version 3 over version 2
  ASSERT_EQ(seen.size(), 2u);
  EXPECT_EQ(seen[1], std::make_pair(uint64_t{5}, uint64_t{2}));
  ASSERT_OK(t->put(5, payload_for(5, 4).data(), nullptr));
  EXPECT_TRUE(t->put(5, payload_for(5, 99).data(), nullptr).is_invalid_argument());
}

}  // namespace
}  // namespace weaver
