// Text from outside (a line of an input file) made safe to echo in a one-line
// error message: bytes that are not printable ASCII become \xNN, and long
// text is cut, so garbage input never writes control bytes to a terminal.
#pragma once

#include <cstdio>
#include <string>
#include <string_view>

namespace weaver {

inline std::string printable(std::string_view s, size_t max_chars = 60) {
  std::string out;
  for (size_t i = 0; i < s.size() && i < max_chars; ++i) {
    const unsigned char c = static_cast<unsigned char>(s[i]);
    if (c >= 0x20 && c < 0x7f && c != '\\') {
      out += static_cast<char>(c);
    } else {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02x", c);
      out += buf;
    }
  }
  if (s.size() > max_chars) out += "...";
  return out;
}

// 3410000 as "3.41M": three significant digits and an SI prefix, for counts,
// rates and sizes in messages.
inline std::string si_text(double v) {
  const char* prefix[] = {"", "K", "M", "G", "T", "P", "E"};
  int p = 0;
  while (v >= 1000 && p < 6) v /= 1000, ++p;
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g%s", v, prefix[p]);
  return buf;
}

}  // namespace weaver
