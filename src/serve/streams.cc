#include "serve/streams.h"

#include <algorithm>
#include <memory>

namespace weaver::serve {
namespace {

struct SinkCookie {
  BodySink* sink;
  uint64_t* written;
};

// A JSON array of points read as text lines: '[' and ']' are dropped (the
// ']' closing a point ends its line), commas become spaces, and a bare
// value at the top level is passed on for the batch to call a bad line.
struct JsonPoints {
  const std::string* body;
  size_t at = 0;
  int depth = 0;

  size_t read(char* out, size_t size) {
    size_t n = 0;
    for (; at < body->size() && n < size; ++at) {
      const char c = (*body)[at];
      if (c == '[') {
        ++depth;
      } else if (c == ']') {
        if (depth-- == 2) out[n++] = '\n';
      } else if (depth >= 2) {
        out[n++] = c == ',' ? ' ' : c;
      } else if (depth == 1 && c != ',' && c != ' ' && c != '\n' && c != '\r' && c != '\t') {
        out[n++] = c;
      }
    }
    return n;
  }
};

// A stdio stream over cookie (mode "r" or "w"); the stream owns the cookie
// from here on, and io.close deletes it.  Null if it cannot be made.
template <typename Cookie>
std::FILE* cookie_stream(std::unique_ptr<Cookie> cookie, const char* mode,
                         cookie_io_functions_t io) {
  io.close = [](void* c) {
    delete static_cast<Cookie*>(c);
    return 0;
  };
  std::FILE* f = fopencookie(cookie.get(), mode, io);
  if (f != nullptr) cookie.release();
  return f;
}

bool is_json_array(const std::string& body) {
  const size_t at = body.find_first_not_of(" \t\r\n");
  return at != std::string::npos && body[at] == '[';
}

}  // namespace

std::FILE* string_stream(std::string* s, size_t cap) {
  struct Capped {
    std::string* s;
    size_t cap;
  };
  cookie_io_functions_t io{};
  io.write = [](void* c, const char* data, size_t n) -> ssize_t {
    auto* k = static_cast<Capped*>(c);
    if (k->s->size() < k->cap) k->s->append(data, std::min(n, k->cap - k->s->size()));
    return ssize_t(n);  // past the cap: taken, and dropped
  };
  return cookie_stream(std::make_unique<Capped>(Capped{s, cap}), "w", io);
}

std::FILE* sink_stream(BodySink* sink, uint64_t* written) {
  cookie_io_functions_t io{};
  io.write = [](void* c, const char* data, size_t n) -> ssize_t {
    auto* k = static_cast<SinkCookie*>(c);
    if (!k->sink->write(data, n)) return -1;  // the client is gone: the query stops
    *k->written += n;
    return ssize_t(n);
  };
  std::FILE* f = cookie_stream(std::make_unique<SinkCookie>(SinkCookie{sink, written}), "w", io);
  if (f != nullptr) std::setvbuf(f, nullptr, _IOFBF, 256 << 10);
  return f;
}

std::FILE* points_stream(const std::string& body) {
  if (!is_json_array(body)) {
    // fmemopen of no bytes fails: an empty body is one empty byte string.
    return fmemopen(const_cast<char*>(body.empty() ? "" : body.data()),
                    body.empty() ? 1 : body.size(), "r");
  }
  auto cookie = std::make_unique<JsonPoints>();
  cookie->body = &body;
  cookie_io_functions_t io{};
  io.read = [](void* c, char* out, size_t size) -> ssize_t {
    return ssize_t(static_cast<JsonPoints*>(c)->read(out, size));
  };
  return cookie_stream(std::move(cookie), "r", io);
}

}  // namespace weaver::serve
