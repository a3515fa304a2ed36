// The sort module: the external sorter (with merge passes when runs outnumber
// its fan-in), sorted spools, and merges of sorted sources, each compared
// with std::sort of the same items.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <random>
#include <vector>

#include "sort/external_sort.h"
#include "sort/sorted_spool.h"
#include "test_util.h"

namespace weaver {
namespace {

std::vector<KeyTag> drain(KeyTagSource& s) {
  std::vector<KeyTag> out;
  KeyTag t;
  bool done = false;
  while (true) {
    EXPECT_OK(s.next(&t, &done));
    if (done) return out;
    out.push_back(t);
  }
}

std::vector<KeyTag> random_items(size_t n, uint64_t key_range, uint32_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<KeyTag> v(n);
  for (auto& item : v) item = {rng() % key_range, rng() % 1000};
  return v;
}

bool same(const std::vector<KeyTag>& a, const std::vector<KeyTag>& b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](auto& x, auto& y) {
           return x.key == y.key && x.tag == y.tag;
         });
}

TEST(ExternalSorter, SortsInMemoryWithoutTouchingTheDisk) {
  testing::TempDir dir;
  ExternalSorter s(dir.file("scratch"), 1 << 20);
  auto items = random_items(10000, 1000, 1);
  for (const auto& i : items) ASSERT_OK(s.add(i));
  ASSERT_OK(s.finish());
  std::sort(items.begin(), items.end());
  EXPECT_TRUE(same(drain(s), items));
  EXPECT_EQ(s.runs_spilled(), 0u);
  EXPECT_FALSE(std::filesystem::exists(dir.file("scratch")));
}

// Budgets so small that the runs outnumber the fan-in several times over:
// the merge passes must keep every item, duplicates included.
TEST(ExternalSorter, MergesInPassesWhenRunsOutnumberTheFanIn) {
  std::vector<uint64_t> budgets = {uint64_t{64} << 10, uint64_t{256} << 10};
  if (!testing::small_scale()) budgets.push_back(uint64_t{1} << 20);  // 18 runs, fan-in 8
  for (uint64_t budget : budgets) {
    testing::TempDir dir;
    auto items = random_items(testing::scaled(600000, 150000), 50000, budget);
    {
      ExternalSorter s(dir.file("scratch"), budget);
      for (const auto& i : items) ASSERT_OK(s.add(i));
      ASSERT_OK(s.finish());
      EXPECT_GT(s.runs_spilled(), 2 * s.max_fan_in()) << budget;
      std::sort(items.begin(), items.end());
      EXPECT_TRUE(same(drain(s), items)) << budget;
    }
    EXPECT_FALSE(std::filesystem::exists(dir.file("scratch"))) << "scratch left behind";
  }
}

// A buffer that starts small (a caller's bound on the items, here far too
// low) grows to its half of the budget before it spills: the same runs as
// a sorter that reserved it all at once, and the same items out.
TEST(ExternalSorter, ABufferStartedSmallGrowsToTheBudgetBeforeSpilling) {
  for (uint64_t budget : {uint64_t{64} << 10, uint64_t{1} << 20, uint64_t{16} << 20}) {
    for (uint64_t expected : {uint64_t{0}, uint64_t{1}, uint64_t{100}}) {
      testing::TempDir dir;
      auto items = random_items(testing::scaled(200000, 50000), 20000, budget + expected);
      ExternalSorter whole(dir.file("whole"), budget);
      ExternalSorter grown(dir.file("grown"), budget, ExternalSorter::Repeats::kKeep, expected);
      for (const auto& i : items) {
        ASSERT_OK(whole.add(i));
        ASSERT_OK(grown.add(i));
      }
      ASSERT_OK(whole.finish());
      ASSERT_OK(grown.finish());
      EXPECT_EQ(grown.runs_spilled(), whole.runs_spilled()) << budget << " " << expected;
      EXPECT_EQ(grown.runs_spilled() == 0, budget == (uint64_t{16} << 20)) << budget;
      std::sort(items.begin(), items.end());
      EXPECT_TRUE(same(drain(grown), items)) << budget << " " << expected;
    }
  }
}

TEST(ExternalSorter, SortsKeyTagsLikeStdSortOverNarrowAndWideKeys) {
  std::mt19937_64 rng(7);
  std::vector<KeyTag> scratch;
  for (int t = 0; t < 100; ++t) {
    // Keys that share low and high bits, as octant keys of one level do.
    const int low = static_cast<int>(rng() % 30), span = 1 + static_cast<int>(rng() % 34);
    const uint64_t high = rng() << (low + span);
    std::vector<KeyTag> items(rng() % 20000);
    for (KeyTag& k : items) k = {high | (rng() % (uint64_t{1} << span)) << low | 5, rng() % 4};
    std::vector<KeyTag> want = items;
    std::sort(want.begin(), want.end());
    sort_key_tags(items, scratch);
    ASSERT_TRUE(same(items, want)) << "low " << low << " span " << span;
  }
}

// A sorter that keeps only the first of each key per run: once repeated
// keys are skipped, the same stream as a sort of everything.
TEST(ExternalSorter, FirstOnlyRunsGiveTheSameFirstOfEachKey) {
  for (uint64_t budget : {uint64_t{64} << 10, uint64_t{64} << 20}) {
    testing::TempDir dir;
    auto items = random_items(testing::scaled(200000, 50000), 30000, 11);
    ExternalSorter s(dir.file("scratch"), budget, ExternalSorter::Repeats::kFirstOnly);
    for (const auto& i : items) ASSERT_OK(s.add(i));
    ASSERT_OK(s.finish());
    std::sort(items.begin(), items.end());
    auto first_of_each = [](std::vector<KeyTag> v) {
      v.erase(std::unique(v.begin(), v.end(),
                          [](const KeyTag& a, const KeyTag& b) { return a.key == b.key; }),
              v.end());
      return v;
    };
    const std::vector<KeyTag> got = drain(s);
    EXPECT_TRUE(std::is_sorted(got.begin(), got.end())) << budget;
    EXPECT_TRUE(same(first_of_each(got), first_of_each(items))) << budget;
    if (s.runs_spilled() == 0) {
      EXPECT_EQ(got.size(), first_of_each(items).size()) << "repeats kept in memory";
    } else {
      EXPECT_LT(got.size(), items.size()) << "no repeats dropped from runs";
    }
  }
}

TEST(SortedSpool, KeepsTheFirstOfRepeatedKeysInMemoryAndWhenSpilled) {
  for (size_t buffer : {size_t{1} << 20, size_t{4096}}) {
    testing::TempDir dir;
    SortedSpool spool(dir.file("s/spool"), buffer);
    std::vector<KeyTag> expect;
    for (uint64_t k = 0; k < 20000; ++k) {
      for (uint64_t rep = 0; rep < k % 3 + 1; ++rep) ASSERT_OK(spool.add({k * 7, rep}));
      expect.push_back({k * 7, 0});
    }
    ASSERT_OK(spool.finish());
    EXPECT_EQ(spool.size(), expect.size());
    EXPECT_EQ(spool.spilled(), buffer < 20000 * sizeof(KeyTag));
    EXPECT_TRUE(same(drain(spool), expect));
  }
}

TEST(SortedSpool, RejectsAKeyBelowTheLastAndReadsOnlyAfterFinish) {
  testing::TempDir dir;
  SortedSpool spool(dir.file("spool"), 4096);
  ASSERT_OK(spool.add({10, 0}));
  KeyTag t;
  bool done = false;
  EXPECT_EQ(spool.next(&t, &done).code(), Status::Code::kInternal);
  const Status st = spool.add({9, 0});
  EXPECT_EQ(st.code(), Status::Code::kInternal);
  EXPECT_NE(st.message().find("key 9 after 10"), std::string::npos) << st.message();
}

TEST(KeyTagMerge, ReadsSortedSourcesAsOne) {
  testing::TempDir dir;
  std::vector<std::unique_ptr<SortedSpool>> spools;
  std::vector<KeyTagSource*> sources;
  std::vector<KeyTag> all;
  std::mt19937_64 rng(7);
  for (int s = 0; s < 5; ++s) {
    spools.push_back(std::make_unique<SortedSpool>(dir.file("sp" + std::to_string(s)), 4096));
    uint64_t key = 0;
    for (int i = 0; i < 3000 * s; ++i) {  // source 0 stays empty
      key += 1 + rng() % 50;
      ASSERT_OK(spools.back()->add({key, uint64_t(s)}));
      all.push_back({key, uint64_t(s)});
    }
    ASSERT_OK(spools.back()->finish());
    sources.push_back(spools.back().get());
  }
  KeyTagMerge merge(sources);
  std::sort(all.begin(), all.end());
  EXPECT_TRUE(same(drain(merge), all));
}

}  // namespace
}  // namespace weaver
