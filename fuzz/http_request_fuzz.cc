// The head of an HTTP request as `weaver serve` reads it from the network:
// request line, target (path, %-escapes, query) and headers, whatever the
// bytes.  The parser must answer (a Request or an error), never crash, and
// keep to its limits.
#include <cstdlib>
#include <string>

#include "serve/http.h"

using namespace weaver;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string head(reinterpret_cast<const char*>(data), size);
  serve::Request r;
  bool too_large = false;
  const Status st = serve::parse_request_head(head, &r, &too_large);
  if (st.ok()) {
    // A parsed request has a method, a path that starts with '/', and no
    // more than its head held.
    if (r.method.empty() || r.path.empty() || r.path.size() > head.size()) std::abort();
    if (r.headers.size() > head.size()) std::abort();
    // RFC 9112's rules held: names are lower-case tokens, values carry no
    // control byte but tabs, an HTTP/1.1 request has one Host.
    for (const auto& [name, value] : r.headers) {
      if (name.empty()) std::abort();
      for (const char c : name) {
        if (c <= ' ' || c == ':' || (c >= 'A' && c <= 'Z') || c == 0x7f) std::abort();
      }
      for (const char c : value) {
        if ((static_cast<unsigned char>(c) < 0x20 && c != '\t') || c == 0x7f) std::abort();
      }
    }
    if (!r.http10 && r.header_count("host") != 1) std::abort();
  } else if (too_large && head.size() <= serve::kMaxRequestLine) {
    std::abort();  // too large only past a limit
  }
  std::string decoded;
  (void)serve::url_decode(head, &decoded);
  return 0;
}
