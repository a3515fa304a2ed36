// util/resolve_split.h: resolve_leaves passes runs of leaves over by
// strides; what it copies and splits must be what a leaf-by-leaf check
// gives, on random octrees with created octants inside some leaves and
// outside all of them.
#include "util/resolve_split.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>
#include <vector>

#include "schema/octant.h"

namespace weaver {
namespace {

// A random refinement of the root, a leaf at most `deepest` levels down.
void refine(uint64_t key, int deepest, std::mt19937_64& rng, std::vector<uint64_t>* leaves) {
  const int level = octant_key_level(key);
  if (level < deepest && (level == 0 || rng() % 3 != 0)) {
    for (int c = 0; c < 8; ++c) refine(octant_key_child(key, c), deepest, rng, leaves);
    return;
  }
  leaves->push_back(key);
}

// A random octant strictly inside `key`, up to `below` levels finer.
uint64_t inside(uint64_t key, int below, std::mt19937_64& rng) {
  const int depth = 1 + static_cast<int>(rng() % below);
  for (int d = 0; d < depth && octant_key_level(key) < kMaxLevel; ++d) {
    key = octant_key_child(key, static_cast<int>(rng() % 8));
  }
  return key;
}

// The slow reference: each leaf looked at alone, split while a created
// octant lies strictly inside.
void reference_split(uint64_t key, const std::set<uint64_t>& created, std::vector<uint64_t>* out) {
  const auto it = created.upper_bound(key);
  if (it == created.end() || *it >= octant_key_subtree_end(key)) {
    out->push_back(key);
    return;
  }
  for (int c = 0; c < 8; ++c) reference_split(octant_key_child(key, c), created, out);
}

TEST(ResolveLeaves, SplitsAndCopiesAsLeafByLeafOnRandomOctrees) {
  std::mt19937_64 rng(51);
  for (int trial = 0; trial < 300; ++trial) {
    std::vector<uint64_t> all;
    refine(/*the root*/ 0, 2 + static_cast<int>(rng() % 4), rng, &all);
    // The leaves are a run of the whole (a subtree among its neighbours);
    // created octants lie in some of them, in the neighbours around, or
    // (trial % 5 == 0) nowhere.
    const size_t first = rng() % all.size();
    const size_t last = first + 1 + rng() % (all.size() - first);
    const std::vector<uint64_t> leaves(all.begin() + first, all.begin() + last);
    std::set<uint64_t> created_set;
    const size_t asks = trial % 5 == 0 ? 0 : 1 + rng() % 12;
    for (size_t a = 0; a < asks; ++a) {
      created_set.insert(inside(all[rng() % all.size()], 3, rng));
    }
    const std::vector<uint64_t> created(created_set.begin(), created_set.end());

    std::vector<uint64_t> want;
    std::vector<size_t> want_from;  // which leaf each came from
    for (size_t i = 0; i < leaves.size(); ++i) {
      reference_split(leaves[i], created_set, &want);
      want_from.resize(want.size(), i);
    }

    std::vector<uint64_t> got;
    std::vector<size_t> got_from;
    std::vector<bool> got_new;
    size_t next_copy = 0;  // runs come in order, each after the last
    const Status st = resolve_leaves(
        leaves.data(), leaves.size(), created,
        [&](size_t begin, size_t end) {
          EXPECT_LT(begin, end);
          EXPECT_GE(begin, next_copy);
          next_copy = end;
          for (size_t i = begin; i < end; ++i) {
            got.push_back(leaves[i]);
            got_from.push_back(i);
            got_new.push_back(false);
          }
          return Status::Ok();
        },
        [&](size_t i, uint64_t key, bool is_new) {
          got.push_back(key);
          got_from.push_back(i);
          got_new.push_back(is_new);
          return Status::Ok();
        });
    ASSERT_TRUE(st.ok());
    ASSERT_EQ(got, want) << "trial " << trial;
    EXPECT_EQ(got_from, want_from) << "trial " << trial;
    for (size_t k = 0; k < got.size(); ++k) {
      // A new leaf is one the split made: not the leaf it came from.
      EXPECT_EQ(got_new[k], got[k] != leaves[got_from[k]]) << "trial " << trial;
    }
  }
}

TEST(ResolveLeaves, LastBelowFindsTheLastSmallerKey) {
  std::mt19937_64 rng(7);
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<uint64_t> keys(1 + rng() % 300);
    for (auto& k : keys) k = rng() % 5000;
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    const size_t from = rng() % keys.size();
    const uint64_t key = keys[from] + 1 + rng() % 3000;
    const size_t want = std::lower_bound(keys.begin(), keys.end(), key) - keys.begin() - 1;
    EXPECT_EQ(last_below(keys.data(), from, keys.size(), key), want) << "trial " << trial;
  }
}

}  // namespace
}  // namespace weaver
