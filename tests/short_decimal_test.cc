// write_short_decimal writes what std::to_chars writes, character for
// character: on the values mesh answers are made of (a few decimals), on
// every kind of float and double drawn at random, and at the edges of its
// fast path (powers of ten, the scientific form's ties, its magnitude
// bounds, the gaps between neighbouring values).
#include "util/short_decimal.h"

#include <gtest/gtest.h>

#include <bit>
#include <random>
#include <string>

namespace weaver {
namespace {

template <typename T>
std::string expected(T v) {
  char b[64];
  return std::string(b, std::to_chars(b, b + sizeof b, v).ptr);
}

template <typename T>
std::string written(T v) {
  char b[64];
  return std::string(b, write_short_decimal(b, v));
}

template <typename T>
void check(T v) {
  ASSERT_EQ(written(v), expected(v))
      << "value bits " << std::bit_cast<std::conditional_t<sizeof(T) == 4, uint32_t, uint64_t>>(v);
}

TEST(ShortDecimal, FewDecimalsAsAnswersHaveThem) {
  std::mt19937_64 rng(51);
  for (int i = 0; i < 2000000; ++i) {
    const int places = int(rng() % 4);
    const double scale = places == 0 ? 1 : places == 1 ? 10 : places == 2 ? 100 : 1000;
    const double magnitude = std::pow(10.0, double(rng() % 14));
    const double v =
        std::floor(double(rng() % (1ull << 53)) / double(1ull << 53) * magnitude * scale) / scale *
        (rng() % 2 ? 1 : -1);
    check(v);
    check(float(v));
  }
}

// Leaf corners and edges in metres: j x (domain edge) / 2^level, binary
// fractions of up to 20 places, and binary fractions of any length.
TEST(ShortDecimal, BinaryFractionsAsCornersAre) {
  std::mt19937_64 rng(49);
  const double edges[] = {100000, 37500, 12500, 1, 3, 250000};
  for (int i = 0; i < 2000000; ++i) {
    const int level = int(rng() % 24);
    const double edge = edges[rng() % 6] / double(uint64_t{1} << level);
    const double v = double(rng() % (uint64_t{1} << (level + 2))) * edge;
    check(v);
    check(-v);
    const int places = int(rng() % 60);
    const double fraction =
        double(rng() >> (rng() % 64)) / std::ldexp(1.0, places) * (rng() % 2 ? 1 : -1);
    check(fraction);
  }
}

TEST(ShortDecimal, AnyBitsAtAll) {
  std::mt19937_64 rng(7);
  for (int i = 0; i < 2000000; ++i) {
    check(std::bit_cast<double>(rng()));
    check(std::bit_cast<float>(uint32_t(rng())));
  }
}

TEST(ShortDecimal, EdgesOfTheFastPath) {
  const double values[] = {0.0,
                           -0.0,
                           1e-3,
                           9.99e-4,
                           0.001,
                           0.005,
                           0.5,
                           1,
                           10,
                           100,
                           1000,
                           10000,
                           100000,
                           1200000,
                           400000,
                           12345678,
                           8191.999,
                           8192,
                           8192.5,
                           8191.5,
                           1e21,
                           1e15,
                           1e16,
                           4398046511103.999,
                           4398046511104.0,
                           390.625,
                           6754.998,
                           0.1,
                           0.3,
                           2831,
                           -1234.5,
                           1e300,
                           5e-324,
                           std::numeric_limits<double>::infinity(),
                           std::numeric_limits<double>::quiet_NaN()};
  for (const double v : values) {
    check(v);
    check(float(v));
    // and the values either side of each
    check(std::nextafter(v, 1e308));
    check(std::nextafter(v, -1e308));
    check(std::nextafter(float(v), 1e30f));
    check(std::nextafter(float(v), -1e30f));
  }
  // every float with 3 decimals up to the fast path's bound
  for (int m = 0; m < 8200000; m += 7) check(float(m) / 1000.0f);
}

}  // namespace
}  // namespace weaver
