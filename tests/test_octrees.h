// Generated octrees shared by the extract and verify tests.
#pragma once

#include <random>
#include <vector>

#include "gen/octree_gen.h"
#include "reference/reference_mesh.h"
#include "test_util.h"

namespace weaver::testing {

// Random refinement of a block domain (bx x by x bz blocks of block_level),
// made balanced by the reference balancer.
inline std::vector<Octant> random_balanced(uint64_t seed, uint32_t bx, uint32_t by, uint32_t bz,
                                           int block_level, uint64_t leaves, int max_level) {
  GenOptions g;
  g.seed = seed;
  g.blocks[0] = bx, g.blocks[1] = by, g.blocks[2] = bz;
  g.block_level = block_level;
  g.leaves = leaves;
  g.max_level = max_level;
  std::vector<Octant> out;
  EXPECT_OK(generate_octree(g, &out));
  return reference::balance(out);
}

// A random refinement of the root with each leaf kept at the odds `keep`:
// holes as fine as the leaves (an imported octree need not fill its
// parents).  Not balanced.
inline std::vector<Octant> random_holed(uint64_t seed, uint64_t leaves, int max_level,
                                        double keep) {
  GenOptions g;
  g.seed = seed;
  g.leaves = leaves;
  g.max_level = max_level;
  std::vector<Octant> all, kept;
  EXPECT_OK(generate_octree(g, &all));
  std::mt19937_64 rng(seed + 1);
  std::bernoulli_distribution coin(keep);
  for (const Octant& o : all) {
    if (coin(rng)) kept.push_back(o);
  }
  return kept;
}

}  // namespace weaver::testing
