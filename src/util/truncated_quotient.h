// trunc(v / d) as the division rounds it, by a product with 1 / d: for a
// constant d the reciprocal is folded when compiled, and a product takes a
// fraction of a division's time.  The rounded product and the rounded
// quotient lie within a few units in the last place of each other, so they
// truncate alike unless the quotient is within that of a whole number;
// there the division itself decides.
#pragma once

#include <cstdint>

namespace weaver {

// REQUIRES: d > 0, v / d < 2^52 (a whole number is exact in a double);
// 0 for v <= 0.
inline uint64_t truncated_quotient(double v, double d) {
  if (v <= 0) return 0;
  // Signed conversions: one instruction each way (the quotient is below 2^52).
  const double p = v * (1 / d);
  const int64_t q = static_cast<int64_t>(p);
  const double frac = p - static_cast<double>(q);
  if (frac < 1e-9 || frac > 1 - 1e-9) return static_cast<uint64_t>(v / d);
  return static_cast<uint64_t>(q);
}

}  // namespace weaver
