// Generated octrees shared by the extract and verify tests.
#pragma once

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

}  // namespace weaver::testing
