// truncated_quotient gives what a division truncated gives, bit for bit: on
// random numbers, and on the whole multiples of the divisor and the doubles
// a few units in the last place on either side, where a product with the
// reciprocal alone truncates differently (the test counts such cases, so it
// fails if the division's fallback goes).
#include "util/truncated_quotient.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace weaver {
namespace {

uint64_t by_division(double v, double d) { return v <= 0 ? 0 : static_cast<uint64_t>(v / d); }

TEST(TruncatedQuotient, AsTheDivisionTruncates) {
  std::mt19937_64 rng(51);
  int product_alone_wrong = 0;
  for (const double d : {600.0, 0.1, 3.0, 7.5, 1e-3, 0.0953674316406250}) {
    std::uniform_real_distribution<double> any(-10 * d, 2e5 * d);
    for (int n = 0; n < 200000; ++n) {
      const double v = any(rng);
      ASSERT_EQ(truncated_quotient(v, d), by_division(v, d)) << v << " / " << d;
    }
    for (int k = 0; k < 20000; ++k) {
      double v = k * d;
      for (int step = 0; step < 4; ++step) v = std::nextafter(v, -HUGE_VAL);
      for (int step = 0; step < 9; ++step, v = std::nextafter(v, HUGE_VAL)) {
        ASSERT_EQ(truncated_quotient(v, d), by_division(v, d)) << v << " / " << d;
        if (v > 0) product_alone_wrong += static_cast<uint64_t>(v * (1 / d)) != by_division(v, d);
      }
    }
  }
  EXPECT_GT(product_alone_wrong, 100);
}

}  // namespace
}  // namespace weaver
