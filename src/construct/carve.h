// The ground's cut through construct's leaves: which side of the surface
// an octant's box lies on, and each kept leaf's solid fraction.
//
// An octant is air when its bottom is at or above the highest ground over
// its footprint (exactly: Surface::range), solid when its top is at or
// below the lowest, else cut.  Air is never an element.  A cut leaf's solid
// fraction is the mean, over 8 x 8 points at the centres of equal parts of
// its footprint, of the share of its height below the ground there (the
// surface bilinear between its grid points).  On a footprint of side h
// where the ground's slope is at most s, each point's share is within
// s h / 16 / height of its part's mean (the midpoint rule on a Lipschitz
// function), so the fraction is within s h / (16 height) = s / 16 for a
// cube: 0.06 at a 45-degree slope, exact where the ground is flat across
// the leaf.  A cut leaf the points all miss (the ground rises into it
// between them) keeps a fraction of at most 1/64, never 0.
#pragma once

#include <cstddef>

#include "construct/construct.h"
#include "model/ground_model.h"

namespace weaver {

struct SubtreeLeaves;

// Drops the air leaves of *leaves and writes the rest's solid fraction into
// the last f32 of each payload (payload_bytes a leaf); recounts its levels,
// elements and edges, and adds the kept ones to its span.  leaves->sides says which leaves the
// descent found wholly below or above the ground (their fraction is 1 or 0: a box inside one on a
// side of the ground is on that side); only the others are computed.  *air and *cut count what it
// dropped and what it cut.
void carve_leaves(const ConstructPlan& p, size_t payload_bytes, SubtreeLeaves* leaves,
                  uint64_t* air, uint64_t* cut);

}  // namespace weaver
