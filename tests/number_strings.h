// Strings at the edges of reading a number: std::from_chars' grammar
// (signs, points, exponents, words, hex), read_decimal's fast path (2^53, 19
// digits, 22 decimals) and the coordinates point files hold.  Shared by the
// tests of the readers built on them (read_decimal, points files' lines).
#pragma once

namespace weaver::testing {

inline constexpr const char* kNumberEdgeCases[] = {
    "0",
    "-0",
    "0.0",
    "-0.0",
    "5.",
    "-5.",
    ".5",
    "-.5",
    "+5",
    "-",
    "",
    ".",
    "1e5",
    "1.5e",
    "1.5e+3",
    "2.5E-2",
    "inf",
    "-inf",
    "nan",
    "0x10",
    "12abc",
    "1.2.3",
    "1,5",
    " 1",
    "9007199254740992",
    "9007199254740993",
    "9007199254740992.5",
    "1234567890123456789",
    "12345678901234567890",
    "0.0000000000000000000001",
    "0.00000000000000000000001",
    "00000000000000000000000001.5",
    "179769313486231570000000000000000000000000000000000000000"
    "0000000000000000000000000000000000000000000000000000000000"
    "0000000000000000000000000000000000000000000000000000000000"
    "000000000000000000000000000000000000000000000000000000000000"
    "000000000000000000000000000000000000.0",
    "24351.78",
    "-1200",
    "0.1",
    "0.3",
    "123456.123456",
    "4.35",
    "8.875"};

}  // namespace weaver::testing
