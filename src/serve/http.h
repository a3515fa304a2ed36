// A small HTTP/1.1 server on POSIX sockets, for `weaver serve`.  One thread
// polls the listening socket and every open connection, and reads requests
// (request line, headers, a body of Content-Length bytes) as their bytes
// arrive; a whole request goes to a pool of worker threads, which answer it
// and hand the connection back for its next request (keep-alive and
// pipelining).  So a slow or idle client holds no thread, only a
// connection.  Bounded everywhere: the request line (8 KiB), the headers
// (32 KiB), a body, the bodies held at once, the requests a connection may
// make, the connections open at once (past them a new one is answered 503
// and closed), and how long a client may take to send a request (408) or
// stay idle between two.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "schema/status.h"
#include "serve/outbox.h"

namespace weaver::serve {

struct Request {
  std::string method;                        // "GET", "POST", ...
  std::string path;                          // the target without its query: "/api/element/5"
  std::map<std::string, std::string> query;  // decoded ?a=1&b=2
  // In the order sent, names in lower case, values without the spaces
  // around them; a header sent twice is here twice.
  std::vector<std::pair<std::string, std::string>> headers;
  std::string body;
  bool http10 = false;     // HTTP/1.0: no chunked answers, close-delimited instead
  bool keep_alive = true;  // HTTP/1.1 unless "Connection: close"
  // The first header of that (lower-case) name, or null.
  const std::string* header(std::string_view name) const {
    for (const auto& [n, v] : headers) {
      if (n == name) return &v;
    }
    return nullptr;
  }
  size_t header_count(std::string_view name) const {
    size_t n = 0;
    for (const auto& h : headers) n += h.first == name;
    return n;
  }
};

// Limits of a request's head.
inline constexpr size_t kMaxRequestLine = 8 << 10;
inline constexpr size_t kMaxHeaders = 32 << 10;

// Parses a request's head (the bytes before "\r\n\r\n"): its line, target
// and headers into *r.  InvalidArgument saying what is wrong, for a reply
// of 400 (or 431 when a limit is passed: *too_large).  Rejects, as RFC 9112
// says a server must or may, rather than repairs: whitespace before a
// header's colon, a folded line (obs-fold), a control byte in a value, a
// header name that is not a token, an HTTP/1.1 request without exactly one
// Host.  What the fuzz target fuzz/http_request_fuzz.cc feeds.
Status parse_request_head(const std::string& head, Request* r, bool* too_large);

// Where a streamed answer writes its body (Response::stream).  The server
// holds the first kStreamHold bytes; an answer that ends within them goes
// out whole with its Content-Length, a longer one goes out as it is written,
// in chunks (Transfer-Encoding: chunked), so that an answer of any size
// holds at most kStreamHold bytes of memory.
class BodySink {
 public:
  virtual ~BodySink() = default;
  // False once the client is gone or too slow: the stream may stop.
  virtual bool write(const char* data, size_t n) = 0;
};
inline constexpr size_t kStreamHold = 1 << 20;

struct Response;
// Writes an answer's body to the sink, and says how it ended: status 200
// (its body unused) or an error response.  An error after the first bytes
// went out closes the connection without the closing chunk, which the
// client sees as a broken transfer.
using BodyStream = std::function<Response(BodySink& sink)>;

struct Response {
  Response(int status_ = 200, std::string type = "application/json", std::string body_ = "",
           std::string cache = "no-store", std::string attachment_ = "")
      : status(status_),
        content_type(std::move(type)),
        body(std::move(body_)),
        cache_control(std::move(cache)),
        attachment(std::move(attachment_)) {}
  int status;
  std::string content_type;
  std::string body;
  std::string cache_control;
  std::string attachment;          // a file name: the browser saves the body as that file
  BodyStream stream;               // set: the body is written by it, not taken from body
  std::shared_ptr<FileBody> file;  // set: the body is this file's bytes
  // More headers, name and value (the page's Content-Security-Policy).
  std::vector<std::pair<std::string, std::string>> extra_headers;
};

// A response with status and a JSON body {"error": message}.
Response error_response(int status, const std::string& message);
// How an answer's body is framed: by Content-Length, in chunks (HTTP/1.1
// answers of unknown length), or by closing the connection (HTTP/1.0's).
enum class Framing { kLength, kChunked, kClose };
// The status line and headers of r.
std::string response_head(const Response& r, bool keep_alive, Framing framing = Framing::kLength);
// The body length a parsed request announces: its Content-Length, 0 without
// one.  An error response (400 for a bad length, for Content-Length headers
// that differ, or for any Transfer-Encoding; 413 past max_body) when it
// cannot be taken: the connection is then closed, as its framing is unknown.
bool body_length(const Request& r, uint64_t max_body, uint64_t* length, Response* error);

struct ServerOptions {
  std::string bind = "127.0.0.1";
  int port = 8080;  // 0: any free port (Server::port() says which)
  int threads = 4;
  uint64_t max_body = 64ull << 20;       // a POST of more is refused (413)
  int timeout_ms = 10000;                // to read a request, and to write its answer
  int idle_ms = 5000;                    // a kept-alive connection idle longer is closed
  int max_requests = 100000;             // on one connection
  int max_connections = 64;              // open at once; past them 503 and closed
  uint64_t max_buffered = 256ull << 20;  // request bodies held at once; past it 503
  // Where the rest of an answer to a slow reader is spilled (serve/outbox.h),
  // and how much may be there at once.
  std::string scratch_dir = ".";
  uint64_t max_spill = 1ull << 30;
  bool log = true;  // a line on stderr for each request
};

class Server {
 public:
  using Handler = std::function<Response(const Request&)>;

  // Binds and listens (InvalidArgument for a bad address, IOError when the
  // port is taken); serve() then answers until stop().
  Status listen(const ServerOptions& o);
  int port() const { return port_; }
  // Runs the pool until stop() (from a signal handler too: it only sets a
  // flag and the threads notice within a fraction of a second).
  // Each thread first runs on_start (if any): its warm-up.
  void serve(const Handler& handler, const std::function<void()>& on_start = nullptr);
  void stop() { stopping_ = true; }
  // Connections open now (for the tests: none leaks).
  int connections() const { return open_; }
  // Body bytes of requests still arriving, counted against max_buffered.
  uint64_t held_bytes() const { return held_; }
  ~Server();

 private:
  ServerOptions o_;
  int listen_fd_ = -1;
  int port_ = 0;
  std::atomic<bool> stopping_{false};
  std::atomic<int> open_{0};
  std::atomic<uint64_t> held_{0};
  SpillRoom spill_;
};

// s with ASCII letters in lower case (header names, host names).
std::string lower_ascii(std::string s);

// "%41" and "+" decoded; InvalidArgument for a bad escape.
Status url_decode(const std::string& in, std::string* out);

}  // namespace weaver::serve
