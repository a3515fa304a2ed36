// Sample octrees for demos and tests (the real construct stage builds from a
// velocity model).  The domain is bx x by x bz blocks of level block_level
// (a non-cube domain is a union of blocks); the leaves tile it exactly.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "schema/octant.h"
#include "schema/status.h"

namespace weaver {

struct GenOptions {
  enum class Kind { kUniform, kRandom };
  Kind kind = Kind::kRandom;
  uint32_t blocks[3] = {1, 1, 1};
  int block_level = 0;
  int level = 6;             // uniform: the leaf level
  uint64_t leaves = 100000;  // random: refine until at least this many leaves
  int max_level = kMaxLevel;  // random: no leaf finer than this
  uint64_t seed = 1;
  bool shuffle = false;  // output in random order instead of key order
};

// The leaves, in key order unless options.shuffle.
Status generate_octree(const GenOptions& options, std::vector<Octant>* leaves);

}  // namespace weaver
