// cli/point_line.h reads a line in one pass; the reference splits it at the
// separators first and reads each token whole with std::from_chars, as the
// points reader did before.  Both must agree on every line: the numbers, bit
// for bit, and the error, word for word.  Lines are made of tokens from a
// list of good and bad numbers and of odd characters, joined by runs of
// separators, with separators before and after, in both units.
#include "cli/point_line.h"

#include <gtest/gtest.h>

#include <bit>
#include <random>
#include <vector>

#include "number_strings.h"

namespace weaver::cli {
namespace {

struct Parsed {
  bool ok = false;
  double v[3] = {0, 0, 0};
  std::string why;
};

Parsed reference(const std::string& line, bool metres) {
  Parsed r;
  std::vector<std::string> tokens;
  std::string token;
  for (char c : line) {
    if (c == ' ' || c == '\t' || c == ',' || c == '\r') {
      if (!token.empty()) tokens.push_back(token), token.clear();
    } else {
      token += c;
    }
  }
  if (!token.empty()) tokens.push_back(token);
  for (size_t i = 0; i < tokens.size(); ++i) {
    if (i == 3) return r.why = "more than 3 numbers", r;
    const std::string& t = tokens[i];
    const char* b = t.data();
    const char* e = b + t.size();
    bool good = false;
    if (metres) {
      double x = 0;
      const auto res = std::from_chars(b, e, x);
      good = res.ec == std::errc() && res.ptr == e && std::isfinite(x);
      r.v[i] = x;
    } else {
      uint64_t x = 0;
      const auto res = std::from_chars(b, e, x);
      good = res.ec == std::errc() && res.ptr == e && x < UINT32_MAX;
      r.v[i] = double(x);
    }
    if (!good) {
      r.why = "'" + printable(t) + "' is not " +
              (metres ? "a number" : "a whole number of ticks (0 to 4294967294)");
      return r;
    }
  }
  if (tokens.size() < 3) return r.why = "expected 3 numbers: x y z", r;
  r.ok = true;
  return r;
}

Parsed one_pass(const std::string& line, bool metres) {
  Parsed r;
  r.ok = parse_point_line(line.data(), line.size(), metres, r.v, &r.why);
  return r;
}

void expect_same(const std::string& line) {
  for (bool metres : {true, false}) {
    const Parsed want = reference(line, metres), got = one_pass(line, metres);
    ASSERT_EQ(got.ok, want.ok) << "'" << line << "' metres " << metres << ": " << got.why;
    if (want.ok) {
      for (int a = 0; a < 3; ++a) {
        ASSERT_EQ(std::bit_cast<uint64_t>(got.v[a]), std::bit_cast<uint64_t>(want.v[a]))
            << "'" << line << "'";
      }
    } else {
      ASSERT_EQ(got.why, want.why) << "'" << line << "' metres " << metres;
    }
  }
}

TEST(PointLine, ReadsWhatSplittingFirstReads) {
  // read_decimal's edge cases, and tokens of ticks and of lines.
  std::vector<std::string> pieces(std::begin(testing::kNumberEdgeCases),
                                  std::end(testing::kNumberEdgeCases));
  pieces.insert(pieces.end(), {"12", "0.5", "1e400", "12-3", "x", "4294967294", "4294967295",
                               "99999999999999999999", "007", "1048575", "3.0517578125", "\xff",
                               "#", "1;2", "\"3\""});
  const std::vector<std::string> separators = {" ", "\t", ",", "\r", "  ", ", ", "\t,\r", ""};
  std::mt19937_64 rng(3);
  for (int line = 0; line < 20000; ++line) {
    std::string s;
    if (rng() % 3 == 0) s += separators[rng() % separators.size()];
    const int tokens = int(rng() % 6);
    for (int t = 0; t < tokens; ++t) {
      if (t > 0) s += separators[rng() % (separators.size() - 1)];  // never none between
      s += pieces[rng() % pieces.size()];
    }
    if (rng() % 3 == 0) s += separators[rng() % separators.size()];
    expect_same(s);
  }
}

TEST(PointLine, CommonShapes) {
  for (const char* s :
       {"1000 2000 3000", "524288,524288,7", "1 2", "12 x 4", "  1048575\t1048575 0  ", "1 2 3 4",
        "1 2 3\r", "", "   ", "24351.78 50220.9 6072.66", "-1 -2 -3", "1e3 2E3 3e-3"}) {
    expect_same(s);
  }
}

}  // namespace
}  // namespace weaver::cli
