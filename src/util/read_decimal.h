// std::from_chars(b, e, v) for a double, the same value and the same end,
// fast for the numbers point files are made of: coordinates with a few
// decimals (24351.78, -1200, 0.5).
//
// from_chars reads such a number in 60 to 100 ns (a tenth of a point query,
// at a million points a second of 3 coordinates).  Here the digits are read
// as a whole number m with d of them after the point; when m < 2^53 and
// d <= 22, both m and 10^d are doubles exactly, so m / 10^d, one IEEE
// division, is the decimal's value correctly rounded: what from_chars
// gives (Clinger's fast path).  Anything else (an exponent, more digits,
// "inf", ".5", a leading '+', nothing to read) goes to from_chars:
// tests/read_decimal_test.cc compares the two on millions of strings.
#pragma once

#include <charconv>
#include <cstdint>
#include <system_error>

namespace weaver {

inline std::from_chars_result read_decimal(const char* b, const char* e, double& v) {
  static constexpr double kPow10[] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                                      1e8,  1e9,  1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
                                      1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};
  const char* p = b;
  const bool negative = p != e && *p == '-';
  p += negative;
  const char* const digits = p;
  uint64_t m = 0;
  int count = 0;  // digits read into m
  for (; p != e && unsigned(*p - '0') < 10; ++p, ++count) m = m * 10 + unsigned(*p - '0');
  if (p == digits) return std::from_chars(b, e, v);  // no whole part: not the fast case
  int decimals = 0;
  if (p != e && *p == '.') {
    for (++p; p != e && unsigned(*p - '0') < 10; ++p, ++decimals, ++count) {
      m = m * 10 + unsigned(*p - '0');
    }
  }
  // 19 digits cannot overflow m; an exponent may follow, and from_chars
  // decides whether it is one.
  if (count > 19 || m > (uint64_t{1} << 53) || decimals > 22 ||
      (p != e && (*p == 'e' || *p == 'E'))) {
    return std::from_chars(b, e, v);
  }
  const double x = double(m) / kPow10[decimals];
  v = negative ? -x : x;
  return {p, std::errc()};
}

}  // namespace weaver
