// One line of a points file: three numbers, x y z, separated by runs of
// spaces, tabs, commas or carriage returns (leading and trailing ones too).
// In metres any decimal std::from_chars reads (util/read_decimal.h); in
// ticks a whole number below 2^32 - 1.
//
// Each number is read in the same pass that finds where it ends: the token
// is taken to end where the number does, and must be followed by a
// separator or the line's end.  (A first pass to find each token's end, then
// a read of the token, read every character twice: a fifth of the parse of
// a million lines, which is the part of `query --points` that no other
// thread shares.)  A number cannot hold a separator, so the tokens, the
// numbers and the errors are those of splitting first.
#pragma once

#include <charconv>
#include <cmath>
#include <cstdint>
#include <string>
#include <string_view>

#include "util/printable.h"
#include "util/read_decimal.h"

namespace weaver::cli {

inline bool is_point_separator(char c) {
  constexpr uint64_t kSeparators =
      uint64_t{1} << ' ' | uint64_t{1} << '\t' | uint64_t{1} << ',' | uint64_t{1} << '\r';
  const auto u = static_cast<unsigned char>(c);
  return u < 64 && ((kSeparators >> u) & 1);
}

// The largest tick a point may have, plus one: 2^32 - 1 stands for "far".
inline constexpr uint64_t kTickLimit = UINT32_MAX;

// Reads the line's three numbers into v; false, with *why saying what is
// wrong, if it does not hold exactly three (in ticks: whole ones below
// kTickLimit; in metres: finite ones).
inline bool parse_point_line(const char* s, size_t n, bool metres, double v[3], std::string* why) {
  const char* const end = s + n;
  const char* p = s;
  int count = 0;
  while (true) {
    while (p != end && is_point_separator(*p)) ++p;
    if (p == end) break;
    if (count == 3) return *why = "more than 3 numbers", false;
    const char* stop = nullptr;
    bool ok = false;
    if (metres) {
      const auto r = read_decimal(p, end, v[count]);
      stop = r.ptr;
      ok = r.ec == std::errc() && std::isfinite(v[count]);
    } else {
      uint64_t t = 0;
      const auto r = std::from_chars(p, end, t);
      stop = r.ptr;
      v[count] = double(t);
      ok = r.ec == std::errc() && t < kTickLimit;
    }
    if (!ok || (stop != end && !is_point_separator(*stop))) {
      const char* token_end = p;
      while (token_end != end && !is_point_separator(*token_end)) ++token_end;
      *why = "'" + printable(std::string_view(p, size_t(token_end - p))) + "' is not " +
             (metres ? "a number" : "a whole number of ticks (0 to 4294967294)");
      return false;
    }
    ++count, p = stop;
  }
  if (count < 3) return *why = "expected 3 numbers: x y z", false;
  return true;
}

}  // namespace weaver::cli
