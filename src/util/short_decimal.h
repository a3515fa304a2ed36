// std::to_chars(p, end, v) for a float or double, the same characters, fast
// for the values a mesh's answers are made of: coordinates in metres and
// velocities with at most 3 decimals (1234.5, 390.625, 6754.998).
//
// The shortest round-trip form is what to_chars writes; finding it takes it
// 25 to 60 ns a value, which at a million rows a second of 7 lengths each is
// most of the time a row takes.  Here, for d = 0, 1, 2, 3 in turn: the decimal
// of d places nearest v, m / 10^d, is checked to read back as v.  The first
// that does is the shortest form (one of fewer places would have read back at
// a smaller d; below the magnitudes allowed, a unit in the last place of v is
// under 10^-3, so it is the only decimal of d places that does).  It is
// written fixed: to_chars writes the scientific form only when it is shorter,
// which with decimal places it never is, nor for a whole number below 10^5.  Anything else (more
// decimals, huge, tiny, zero, not finite) goes to to_chars too: tests/short_decimal_test.cc
// compares the two on millions of values.
#pragma once

#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <limits>

namespace weaver {
namespace short_decimal_detail {

// Writes m / 10^d fixed, with its sign.
inline char* write_fixed(char* p, bool negative, uint64_t m, int d) {
  uint64_t whole = m, frac = 0;
  switch (d) {  // constant divisors: a multiply each, not a division
    case 1: whole = m / 10, frac = m % 10; break;
    case 2: whole = m / 100, frac = m % 100; break;
    case 3: whole = m / 1000, frac = m % 1000; break;
    default: break;
  }
  if (negative) *p++ = '-';
  p = std::to_chars(p, p + 24, whole).ptr;
  if (d > 0) {
    *p++ = '.';
    for (int i = d - 1; i >= 0; --i) p[i] = char('0' + frac % 10), frac /= 10;
    p += d;
  }
  return p;
}

template <typename T>
char* write(char* p, T v) {
  constexpr bool kFloat = std::numeric_limits<T>::digits == 24;
  // Below this magnitude a unit in v's last place is under 10^-3: 2^13 for
  // a float (2^-11), 2^42 for a double (2^-11 too).
  constexpr T kMax = kFloat ? T(8192) : T(4398046511104.0);
  const T a = std::fabs(v);
  if (!(a >= T(0.001) && a < kMax)) return std::to_chars(p, p + 40, v).ptr;
  const double x = double(a);
  // A float's gaps to its neighbours (a is normal and positive here).
  double up = 0, down = 0;
  if constexpr (kFloat) {
    const uint32_t bits = std::bit_cast<uint32_t>(a);
    up = double(std::bit_cast<float>(bits + 1)) - x;
    down = x - double(std::bit_cast<float>(bits - 1));
  }
  constexpr double kScale[4] = {1, 10, 100, 1000};
  for (int d = 0; d <= 3; ++d) {
    const double scaled = x * kScale[d];  // exact for a float, not for a double
    const uint64_t m = uint64_t(scaled + 0.5);
    const double md = double(m);
    // m / 10^d reads back as a: for a double, the division is rounded as
    // reading the decimal is; for a float, m / 10^d lies strictly within half
    // a gap of a (exact arithmetic: 24 bits times 10^3 fit in a double).
    const bool reads_back =
        kFloat ? md - scaled < up * kScale[d] / 2 && scaled - md < down * kScale[d] / 2
               : md / kScale[d] == x;
    if (!reads_back) continue;
    // With places the fixed form is never the longer; a whole number from
    // 100000 up may be shorter as 1e+05: to_chars decides.
    if (d == 0 && m >= 100000) break;
    return write_fixed(p, v < 0, m, d);
  }
  return std::to_chars(p, p + 40, v).ptr;
}

}  // namespace short_decimal_detail

// Writes v at p as std::to_chars(p, p + 40, v) would; returns the end.
inline char* write_short_decimal(char* p, double v) { return short_decimal_detail::write(p, v); }
inline char* write_short_decimal(char* p, float v) { return short_decimal_detail::write(p, v); }

}  // namespace weaver
