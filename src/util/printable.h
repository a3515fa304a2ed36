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

}  // namespace weaver
