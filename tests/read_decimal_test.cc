// read_decimal reads what std::from_chars reads, bit for bit and to the same
// end: on the numbers point files hold, on random digit strings around the
// fast path's bounds (2^53, 19 digits, 22 decimals), on every double printed
// shortest, and on the odd cases that must go to from_chars.
#include "util/read_decimal.h"

#include <gtest/gtest.h>

#include <bit>
#include <cstdio>
#include <random>
#include <string>

#include "number_strings.h"

namespace weaver {
namespace {

void check(const std::string& s) {
  double want = 12345.0, got = 12345.0;  // both untouched when nothing is read
  const auto w = std::from_chars(s.data(), s.data() + s.size(), want);
  const auto g = read_decimal(s.data(), s.data() + s.size(), got);
  ASSERT_EQ(int(g.ec), int(w.ec)) << "'" << s << "'";
  ASSERT_EQ(g.ptr - s.data(), w.ptr - s.data()) << "'" << s << "'";
  if (w.ec == std::errc()) {
    ASSERT_EQ(std::bit_cast<uint64_t>(got), std::bit_cast<uint64_t>(want)) << "'" << s << "'";
  }
}

TEST(ReadDecimal, EdgesAndOddCases) {
  for (const char* s : testing::kNumberEdgeCases) {
    check(s);
  }
}

TEST(ReadDecimal, CoordinatesAsPointFilesWriteThem) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-2e5, 2e5);
  char b[64];
  for (int i = 0; i < 1000000; ++i) {
    const double x = u(rng);
    const int decimals = int(rng() % 7);
    std::snprintf(b, sizeof b, "%.*f", decimals, x);
    check(b);
  }
}

TEST(ReadDecimal, RandomDigitsAroundTheFastPathsBounds) {
  std::mt19937_64 rng(11);
  for (int i = 0; i < 1000000; ++i) {
    std::string s = rng() % 4 == 0 ? "-" : "";
    const int whole = 1 + int(rng() % 20), decimals = int(rng() % 26);
    for (int k = 0; k < whole; ++k) s += char('0' + rng() % 10);
    if (decimals > 0 || rng() % 8 == 0) s += '.';
    for (int k = 0; k < decimals; ++k) s += char('0' + rng() % 10);
    if (rng() % 16 == 0) s += " 7";  // text after the number
    check(s);
  }
}

TEST(ReadDecimal, EveryKindOfDoubleWrittenShortest) {
  std::mt19937_64 rng(13);
  char b[64];
  for (int i = 0; i < 1000000; ++i) {
    const double v = std::bit_cast<double>(rng());
    const auto r = std::to_chars(b, b + sizeof b, v, std::chars_format::fixed);
    if (r.ec == std::errc() && r.ptr - b < 40) check(std::string(b, r.ptr));
    check(std::string(b, std::to_chars(b, b + sizeof b, v).ptr));
  }
}

}  // namespace
}  // namespace weaver
