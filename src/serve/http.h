// A small HTTP/1.1 server on POSIX sockets, for `weaver serve`: a listening
// socket and a pool of threads, each accepting a connection, reading one
// request (request line, headers, a body of Content-Length bytes) and
// writing one response, then closing it.  Bounded everywhere: the head of a
// request, its body, and how long a client may take to send them.
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
};

struct Response {
  int status = 200;
  std::string content_type = "application/json";
  std::string body;
  std::string cache_control = "no-store";
};

// A response with status and a JSON body {"error": message}.
Response error_response(int status, const std::string& message);

struct ServerOptions {
  std::string bind = "127.0.0.1";
  int port = 8080;  // 0: any free port (Server::port() says which)
  int threads = 4;
  uint64_t max_body = 64ull << 20;  // a POST of more is refused (413)
  int timeout_ms = 10000;           // to read a request, and to write its answer
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
  void serve(const Handler& handler);
  void stop() { stopping_ = true; }
  ~Server();

 private:
  void worker(const Handler& handler);
  void answer(int fd, const Handler& handler);

  ServerOptions o_;
  int listen_fd_ = -1;
  int port_ = 0;
  std::atomic<bool> stopping_{false};
};

// "%41" and "+" decoded; InvalidArgument for a bad escape.
Status url_decode(const std::string& in, std::string* out);

}  // namespace weaver::serve
