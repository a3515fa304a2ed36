// A string as a JSON string literal: quoted, with '"', '\' and control
// characters escaped.  Other bytes pass as they are (paths are UTF-8 here).
#pragma once

#include <cstdio>
#include <string>

namespace weaver {

inline std::string json_string(const std::string& s) {
  std::string out = "\"";
  for (const char ch : s) {
    const unsigned char c = static_cast<unsigned char>(ch);
    if (c == '"' || c == '\\') {
      out += '\\', out += ch;
    } else if (c < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", c);
      out += buf;
    } else {
      out += ch;
    }
  }
  return out + "\"";
}

}  // namespace weaver
