// std::to_chars(p, end, v) for a float or double, the same characters, fast
// for the values a mesh's answers are made of: coordinates in metres and
// velocities with at most 3 decimals (1234.5, 390.625, 6754.998).
//
// The shortest round-trip form is what to_chars writes; finding it takes it
// 25 to 60 ns a value, which at a million rows a second of 7 lengths each is
// most of the time a row takes.  Here the decimal of 3 places nearest v is
// checked to read back as v; below the magnitudes allowed, a unit in the last
// place of v is under 10^-3, so no other decimal of 3 places or fewer does,
// and that one without its trailing zeros is the shortest form.  It is
// written fixed: to_chars writes the scientific form only when it is
// shorter, which with decimal places it never is, nor for a whole number
// below 10^5.  A double that is a short binary fraction (a leaf's corner in
// metres, 24316.40625) is written as its exact decimal (write_dyadic).
// Anything else (more decimals, huge, tiny, zero, not finite) goes to
// to_chars: tests/short_decimal_test.cc compares the two on millions of
// values.
#pragma once

#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <limits>

namespace weaver {
namespace short_decimal_detail {

// Writes whole.frac fixed, with its sign, frac as d digits (none: no point).
inline char* write_parts(char* p, bool negative, uint64_t whole, uint64_t frac, int d) {
  if (negative) *p++ = '-';
  p = std::to_chars(p, p + 24, whole).ptr;
  if (d > 0) {
    *p++ = '.';
    for (int i = d - 1; i >= 0; --i) p[i] = char('0' + frac % 10), frac /= 10;
    p += d;
  }
  return p;
}

// Writes m / 10^d fixed, with its sign.  REQUIRES: d <= 3.
inline char* write_fixed(char* p, bool negative, uint64_t m, int d) {
  uint64_t whole = m, frac = 0;
  switch (d) {  // constant divisors: a multiply each, not a division
    case 1: whole = m / 10, frac = m % 10; break;
    case 2: whole = m / 100, frac = m % 100; break;
    case 3: whole = m / 1000, frac = m % 1000; break;
    default: break;
  }
  return write_parts(p, negative, whole, frac, d);
}

// A double that is a binary fraction M / 2^k (M odd, k > 0: a leaf's corner
// or edge in metres, 12.20703125) is the decimal M 5^k / 10^k exactly, of k
// places.  When that has at most 15 significant digits it is the shortest
// form that reads back as x: two decimals of 15 digits or fewer never read
// as one double (DBL_DIG), so no shorter one does.  Written fixed, as
// to_chars does for x >= 0.001 (at most two zeros after the point: the
// scientific form is never shorter).  Null when x is not such a fraction.
// REQUIRES: 0.001 <= x < 2^42.
inline char* write_dyadic(char* p, bool negative, double x) {
  static constexpr uint64_t kPow5[] = {1,
                                       5,
                                       25,
                                       125,
                                       625,
                                       3125,
                                       15625,
                                       78125,
                                       390625,
                                       1953125,
                                       9765625,
                                       48828125,
                                       244140625,
                                       1220703125,
                                       6103515625,
                                       30517578125,
                                       152587890625,
                                       762939453125,
                                       3814697265625,
                                       19073486328125,
                                       95367431640625,
                                       476837158203125};
  constexpr uint64_t kDigits15 = 1000000000000000;  // 10^15
  const uint64_t bits = std::bit_cast<uint64_t>(x);
  uint64_t m = (bits & ((uint64_t{1} << 52) - 1)) | uint64_t{1} << 52;
  int e = int(bits >> 52) - 1075;  // x = m 2^e (normal: x >= 0.001)
  const int zeros = std::countr_zero(m);
  m >>= zeros, e += zeros;
  const int k = -e;
  if (k <= 0 || k >= 22 || m >= kDigits15 / kPow5[k]) return nullptr;  // m 5^k < 10^15
  // x = m / 2^k = (m 5^k) / 10^k: the whole part is m's bits above k, and
  // the k decimals are its bits below k times 5^k (under 10^15: checked).
  const uint64_t frac = (m & ((uint64_t{1} << k) - 1)) * kPow5[k];
  return write_parts(p, negative, m >> k, frac, k);
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
  // The decimal of 3 places nearest a, m / 1000: it reads back as a when,
  // for a double, the division is rounded as reading the decimal is; for a
  // float, when m / 1000 lies strictly within half a gap of a (exact
  // arithmetic: 24 bits times 10^3 fit in a double).
  const double scaled = x * 1000;  // exact for a float, not for a double
  uint64_t m = uint64_t(scaled + 0.5);
  const double md = double(m);
  const bool reads_back =
      kFloat ? md - scaled < up * 500 && scaled - md < down * 500 : md / 1000 == x;
  if (reads_back) {
    // It is the only decimal of 3 places or fewer that does (they are 10^-3
    // apart; the values that read back as a, less than that): without its
    // trailing zeros, the shortest form.
    int d = 3;
    while (d > 0 && m % 10 == 0) m /= 10, --d;
    // With places the fixed form is never the longer; a whole number from
    // 100000 up may be shorter as 1e+05: to_chars decides.
    if (d > 0 || m < 100000) return write_fixed(p, v < 0, m, d);
  }
  if constexpr (!kFloat) {
    if (char* end = write_dyadic(p, v < 0, x)) return end;
  }
  return std::to_chars(p, p + 40, v).ptr;
}

}  // namespace short_decimal_detail

// Writes v at p as std::to_chars(p, p + 40, v) would; returns the end.
inline char* write_short_decimal(char* p, double v) { return short_decimal_detail::write(p, v); }
inline char* write_short_decimal(char* p, float v) { return short_decimal_detail::write(p, v); }

}  // namespace weaver
