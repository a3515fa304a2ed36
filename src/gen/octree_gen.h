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
  // kSphere: graded around a sphere at the centre of the root (radius
  // `radius` x root edge): every octant closer to it than 2 x its own edge is
  // refined, from `level` down to `max_level`.  The factor 2 makes the result
  // face+edge 2:1 balanced by construction (a leaf next to one two levels
  // finer would be within 2 of its own edges of the sphere).
  // kPoints: the same rule around `points` random points: scattered random
  // refinement, also 2:1 balanced by construction (the argument only needs
  // one distance function and one finest level).
  enum class Kind { kUniform, kRandom, kSphere, kPoints };
  Kind kind = Kind::kRandom;
  uint32_t blocks[3] = {1, 1, 1};
  int block_level = 0;
  int level = 6;              // uniform: the leaf level
  uint64_t leaves = 100000;   // random: refine until at least this many leaves
  int max_level = kMaxLevel;  // random: no leaf finer than this
  double radius = 0.3;        // sphere: radius as a fraction of the root edge
  uint64_t points = 1000;     // points: how many
  uint64_t seed = 1;
  bool shuffle = false;  // output in random order instead of key order
};

// The leaves, in key order unless options.shuffle.
Status generate_octree(const GenOptions& options, std::vector<Octant>* leaves);

}  // namespace weaver
