// A small HTTP/1.1 server on POSIX sockets, for `weaver serve`: a listening
// socket and a pool of threads, each accepting a connection and answering
// its requests (request line, headers, a body of Content-Length bytes) one
// after another while the client keeps it alive.  Bounded everywhere: the
// request line (8 KiB), the headers (32 KiB), the body, the requests a
// connection may make, the connections served at once (the threads; the
// rest wait in the kernel's queue), and how long a client may take to send
// a request or stay idle between two.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <string>

#include "schema/status.h"

namespace weaver::serve {

struct Request {
  std::string method;                          // "GET", "POST", ...
  std::string path;                            // the target without its query: "/api/element/5"
  std::map<std::string, std::string> query;    // decoded ?a=1&b=2
  std::map<std::string, std::string> headers;  // names in lower case
  std::string body;
  bool keep_alive = true;  // HTTP/1.1 unless "Connection: close"
};

// Limits of a request's head.
inline constexpr size_t kMaxRequestLine = 8 << 10;
inline constexpr size_t kMaxHeaders = 32 << 10;

// Parses a request's head (the bytes before "\r\n\r\n"): its line, target
// and headers into *r.  InvalidArgument saying what is wrong, for a reply
// of 400 (or 431 when a limit is passed: *too_large).  What the fuzz target
// fuzz/http_request_fuzz.cc feeds.
Status parse_request_head(const std::string& head, Request* r, bool* too_large);

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
  std::string attachment;  // a file name: the browser saves the body as that file
};

// A response with status and a JSON body {"error": message}.
Response error_response(int status, const std::string& message);

struct ServerOptions {
  std::string bind = "127.0.0.1";
  int port = 8080;  // 0: any free port (Server::port() says which)
  int threads = 4;
  uint64_t max_body = 64ull << 20;  // a POST of more is refused (413)
  int timeout_ms = 10000;           // to read a request, and to write its answer
  int idle_ms = 1000;               // a kept-alive connection idle longer is closed
  int max_requests = 100000;        // on one connection
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
  ~Server();

 private:
  void worker(const Handler& handler, const std::function<void()>& on_start);
  void answer(int fd, const Handler& handler);

  ServerOptions o_;
  int listen_fd_ = -1;
  int port_ = 0;
  std::atomic<bool> stopping_{false};
};

// "%41" and "+" decoded; InvalidArgument for a bad escape.
Status url_decode(const std::string& in, std::string* out);

}  // namespace weaver::serve
