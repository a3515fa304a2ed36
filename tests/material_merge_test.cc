// MaterialMerger against a slow, obviously correct reference: the whole
// octree in a map, merged level by level from the finest up.
#include "model/material_merge.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <vector>

namespace weaver {
namespace {

struct Value {
  ModelValues mean, low, high;
};

// A random linear octree under `root` (leaves in key order), in which some
// subtrees hold one value throughout and others a value near a common one.
void grow(const Octant& o, std::mt19937_64& rng, const ModelValues* fill, int max_level,
          std::vector<std::pair<Octant, ModelValues>>* out) {
  std::uniform_real_distribution<double> u(0, 1);
  if (o.level < max_level && u(rng) < (o.level < 2 ? 0.9 : 0.55)) {
    ModelValues shared{};
    const ModelValues* child_fill = fill;
    if (!fill && u(rng) < 0.35) {
      for (float& f : shared) f = float(1000 + std::floor(u(rng) * 4) * 100);
      child_fill = &shared;
    }
    for (int c = 0; c < 8; ++c) grow(octant_child(o, c), rng, child_fill, max_level, out);
    return;
  }
  ModelValues v{};
  for (int f = 0; f < kModelFields; ++f) {
    // Filled regions: the shared value, or within 5% of it.
    v[f] = fill ? float((*fill)[f] * (u(rng) < 0.5 ? 1.0 : 1.0 + 0.05 * u(rng)))
                : float(500 + 3000 * u(rng));
  }
  out->push_back({o, v});
}

std::map<uint64_t, Value> reference(const std::vector<std::pair<Octant, ModelValues>>& leaves,
                                    double tolerance, int fields) {
  std::map<uint64_t, Value> tree;
  for (const auto& [o, v] : leaves) tree[octant_key(o)] = {v, v, v};
  for (int level = kMaxLevel; level >= 1; --level) {
    std::map<uint64_t, Octant> parents;
    for (const auto& [k, v] : tree) {
      const Octant o = octant_from_key(k);
      if (o.level == level) parents[octant_key(octant_parent(o))] = octant_parent(o);
    }
    for (const auto& [pk, p] : parents) {
      std::vector<Value> kids;
      for (int c = 0; c < 8; ++c) {
        auto it = tree.find(octant_key(octant_child(p, c)));
        if (it != tree.end()) kids.push_back(it->second);
      }
      if (kids.size() < 8) continue;
      bool same = true;
      Value merged = kids[0];
      for (int f = 0; f < fields; ++f) {
        float low = kids[0].low[f], high = kids[0].high[f];
        double sum = 0;
        for (const Value& k : kids) {
          low = std::min(low, k.low[f]);
          high = std::max(high, k.high[f]);
          sum += k.mean[f];
        }
        same = same && (tolerance == 0 ? low == high : high - low <= tolerance * std::abs(low));
        merged.low[f] = low, merged.high[f] = high, merged.mean[f] = float(sum / 8);
      }
      if (!same) continue;
      for (int c = 0; c < 8; ++c) tree.erase(octant_key(octant_child(p, c)));
      tree[pk] = merged;
    }
  }
  return tree;
}

TEST(MaterialMerger, MatchesTheReferenceOnRandomOctrees) {
  std::mt19937_64 rng(7);
  int merged_somewhere = 0;
  for (int trial = 0; trial < 160; ++trial) {
    std::vector<std::pair<Octant, ModelValues>> leaves;
    const int max_level = 3 + trial % 4;
    // Whole octrees, and domains that are a few blocks of one (holes).
    if (trial % 3 == 0) {
      for (int c = 0; c < 8; ++c) {
        if (rng() % 3 != 0) grow(octant_child(octant_root(), c), rng, nullptr, max_level, &leaves);
      }
    } else {
      grow(octant_root(), rng, nullptr, max_level, &leaves);
    }
    const double tolerance = trial % 2 ? 0.0 : 0.06;
    const int fields = trial % 4 == 1 ? 3 : kModelFields;
    std::vector<std::pair<uint64_t, ModelValues>> got;
    MaterialMerger m(tolerance, fields, [&](uint64_t k, const ModelValues& v) {
      got.push_back({k, v});
      return Status::Ok();
    });
    for (const auto& [o, v] : leaves) ASSERT_TRUE(m.add(o, v).ok());
    ASSERT_TRUE(m.finish().ok());
    const auto want = reference(leaves, tolerance, fields);
    ASSERT_EQ(got.size(), want.size()) << "trial " << trial;
    auto it = want.begin();
    for (size_t i = 0; i < got.size(); ++i, ++it) {
      ASSERT_EQ(got[i].first, it->first) << "trial " << trial << " octant " << i;
      for (int f = 0; f < fields; ++f) ASSERT_EQ(got[i].second[f], it->second.mean[f]);
    }
    merged_somewhere += got.size() < leaves.size();
  }
  EXPECT_GT(merged_somewhere, 50);  // the trees did have something to merge
}

TEST(MaterialMerger, NeverStraysFurtherThanTheTolerance) {
  std::mt19937_64 rng(11);
  std::vector<std::pair<Octant, ModelValues>> leaves;
  grow(octant_root(), rng, nullptr, 7, &leaves);
  std::vector<std::pair<uint64_t, ModelValues>> got;
  MaterialMerger m(0.06, kModelFields, [&](uint64_t k, const ModelValues& v) {
    got.push_back({k, v});
    return Status::Ok();
  });
  for (const auto& [o, v] : leaves) ASSERT_TRUE(m.add(o, v).ok());
  ASSERT_TRUE(m.finish().ok());
  // Every input leaf lies in one output octant, whose value is within 6%.
  for (const auto& [o, v] : leaves) {
    auto it = std::upper_bound(got.begin(), got.end(), octant_key(o),
                               [](uint64_t k, const auto& e) { return k < e.first; });
    ASSERT_NE(it, got.begin());
    --it;
    ASSERT_TRUE(octant_is_ancestor(octant_from_key(it->first), o) || octant_key(o) == it->first);
    for (int f = 0; f < kModelFields; ++f) {
      EXPECT_LE(std::abs(it->second[f] - v[f]), 0.06 * v[f] + 1e-3);
    }
  }
}

}  // namespace
}  // namespace weaver
