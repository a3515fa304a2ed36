// The check both models' tests make of VelocityModel::vs_bounds_of_eighths:
// the eight halves' bounds at once are those of eight vs_bounds calls.
#pragma once

#include <gtest/gtest.h>

#include "model/velocity_model.h"

namespace weaver {

// Asks m for the bounds of the halves c with want[c] of the box whose sides
// on axis a are edges[a][0..2], at once and one at a time; they must agree
// bit for bit, refusals included.  Counts the halves bounded and refused.
inline void expect_eighths_as_calls(const VelocityModel& m, const double edges[3][3],
                                    const bool want[8], int* bounded, int* refused) {
  float got_lo[8] = {}, got_hi[8] = {};
  bool ok[8] = {};
  m.vs_bounds_of_eighths(edges, want, got_lo, got_hi, ok);
  for (int c = 0; c < 8; ++c) {
    if (!want[c]) continue;
    double lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      const int b = (c >> a) & 1;
      lo[a] = edges[a][b], hi[a] = edges[a][b + 1];
    }
    float want_lo = 0, want_hi = 0;
    const bool want_ok = m.vs_bounds(lo, hi, &want_lo, &want_hi);
    ASSERT_EQ(ok[c], want_ok) << "half " << c << " of the box at " << edges[0][0] << " "
                              << edges[1][0] << " " << edges[2][0];
    *refused += !want_ok;
    if (!want_ok) continue;
    ASSERT_EQ(got_lo[c], want_lo) << "half " << c << " of the box at " << edges[0][0] << " "
                                  << edges[1][0] << " " << edges[2][0];
    ASSERT_EQ(got_hi[c], want_hi) << "half " << c << " of the box at " << edges[0][0] << " "
                                  << edges[1][0] << " " << edges[2][0];
    ++*bounded;
  }
}

}  // namespace weaver
