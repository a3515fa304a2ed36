#include "serve/http.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <thread>
#include <vector>

#include "util/json_string.h"

namespace weaver::serve {
namespace {

const char* reason(int status) {
  switch (status) {
    case 200: return "OK";
    case 400: return "Bad Request";
    case 404: return "Not Found";
    case 405: return "Method Not Allowed";
    case 408: return "Request Timeout";
    case 413: return "Payload Too Large";
    case 431: return "Request Header Fields Too Large";
    case 500: return "Internal Server Error";
    case 503: return "Service Unavailable";
    default: return "Error";
  }
}

// A connection's bytes, read as requests arrive (pipelined ones included).
class Reader {
 public:
  // Waits for bytes at most timeout_ms at a time, and gives up as soon as
  // the server stops.
  Reader(int fd, int timeout_ms, const std::atomic<bool>& stopping)
      : fd_(fd), timeout_ms_(timeout_ms), stopping_(stopping) {}
  // The next request's head; false on close, timeout (*status 408) or a head
  // past the limits (431).
  bool head(std::string* out, int* status) {
    *status = 0;
    for (;;) {
      const size_t end = buf_.find("\r\n\r\n");
      if (end != std::string::npos) {
        *out = buf_.substr(0, end);
        buf_.erase(0, end + 4);
        return true;
      }
      if (buf_.size() > kMaxRequestLine + kMaxHeaders) return *status = 431, false;
      if (!more()) return *status = buf_.empty() ? 0 : 408, false;
    }
  }
  // n bytes of body.
  bool body(uint64_t n, std::string* out) {
    while (buf_.size() < n) {
      if (!more()) return false;
    }
    if (buf_.size() == n) {  // the usual case: no copy of a large body
      out->swap(buf_);
      buf_.clear();
      return true;
    }
    out->assign(buf_, 0, n);
    buf_.erase(0, n);
    return true;
  }
  bool pending() const { return !buf_.empty(); }

 private:
  bool more() {
    for (int waited = 0;; waited += 200) {
      if (stopping_ || waited >= timeout_ms_) return false;
      pollfd p{fd_, POLLIN, 0};
      const int ready = ::poll(&p, 1, 200);
      if (ready > 0) break;
      if (ready < 0 && errno != EINTR) return false;
    }
    char chunk[1 << 16];
    const ssize_t n = ::recv(fd_, chunk, sizeof chunk, 0);
    if (n <= 0) return false;
    buf_.append(chunk, size_t(n));
    return true;
  }
  int fd_;
  int timeout_ms_;
  const std::atomic<bool>& stopping_;
  std::string buf_;
};

std::string lower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

Status parse_query(const std::string& qs, Request* r) {
  for (size_t from = 0; from <= qs.size();) {
    size_t amp = qs.find('&', from);
    if (amp == std::string::npos) amp = qs.size();
    const std::string pair = qs.substr(from, amp - from);
    const size_t eq = pair.find('=');
    std::string k, v;
    WEAVER_RETURN_IF_ERROR(url_decode(pair.substr(0, eq), &k));
    if (eq != std::string::npos) WEAVER_RETURN_IF_ERROR(url_decode(pair.substr(eq + 1), &v));
    if (!k.empty()) r->query[k] = v;
    from = amp + 1;
  }
  return Status::Ok();
}

bool send_all(int fd, const std::string& data) {
  for (size_t sent = 0; sent < data.size();) {
    const ssize_t n = ::send(fd, data.data() + sent, data.size() - sent, MSG_NOSIGNAL);
    if (n <= 0) return false;
    sent += size_t(n);
  }
  return true;
}

bool respond(int fd, const Response& r, bool keep_alive) {
  std::string head = "HTTP/1.1 " + std::to_string(r.status) + " " + reason(r.status) + "\r\n";
  head += "Content-Type: " + r.content_type + "\r\n";
  head += "Content-Length: " + std::to_string(r.body.size()) + "\r\n";
  head += "Cache-Control: " + r.cache_control + "\r\n";
  if (!r.attachment.empty()) {
    head += "Content-Disposition: attachment; filename=\"" + r.attachment + "\"\r\n";
  }
  head += "X-Content-Type-Options: nosniff\r\n";
  head += keep_alive ? "Connection: keep-alive\r\n\r\n" : "Connection: close\r\n\r\n";
  // One send for a small answer: two would wait on the client's delayed ACK.
  if (r.body.size() < (256 << 10)) return send_all(fd, head + r.body);
  return send_all(fd, head) && send_all(fd, r.body);
}

}  // namespace

Response error_response(int status, const std::string& message) {
  return {status, "application/json", "{\"error\": " + json_string(message) + "}\n"};
}

Status url_decode(const std::string& in, std::string* out) {
  out->clear();
  for (size_t i = 0; i < in.size(); ++i) {
    if (in[i] == '+') {
      *out += ' ';
    } else if (in[i] == '%') {
      if (i + 2 >= in.size() || !std::isxdigit(static_cast<unsigned char>(in[i + 1])) ||
          !std::isxdigit(static_cast<unsigned char>(in[i + 2]))) {
        return Status::InvalidArgument("bad %-escape in '" + in + "'");
      }
      *out += char(std::stoi(in.substr(i + 1, 2), nullptr, 16));
      i += 2;
    } else {
      *out += in[i];
    }
  }
  return Status::Ok();
}

Status parse_request_head(const std::string& head, Request* r, bool* too_large) {
  *too_large = false;
  *r = Request{};
  const size_t line_end = std::min(head.find("\r\n"), head.size());
  if (line_end > kMaxRequestLine) {
    *too_large = true;
    return Status::InvalidArgument("the request line is longer than 8 KiB");
  }
  if (head.size() - line_end > kMaxHeaders) {
    *too_large = true;
    return Status::InvalidArgument("the headers are longer than 32 KiB");
  }
  const std::string line = head.substr(0, line_end);
  // METHOD SP TARGET SP VERSION: a method of capitals, a target without
  // spaces or control bytes.
  const size_t sp1 = line.find(' '), sp2 = line.rfind(' ');
  if (sp1 == 0 || sp1 == std::string::npos || sp2 <= sp1 + 1) {
    return Status::InvalidArgument("malformed request line");
  }
  r->method = line.substr(0, sp1);
  const std::string target = line.substr(sp1 + 1, sp2 - sp1 - 1);
  for (const char c : r->method) {
    if (c < 'A' || c > 'Z') return Status::InvalidArgument("malformed request method");
  }
  for (const char c : target) {
    if (static_cast<unsigned char>(c) <= 0x20 || c == 0x7f) {
      return Status::InvalidArgument("malformed request target");
    }
  }
  const std::string version = line.substr(sp2 + 1);
  if (version != "HTTP/1.1" && version != "HTTP/1.0") {
    return Status::InvalidArgument("not HTTP/1.0 or HTTP/1.1");
  }
  if (target.empty() || target[0] != '/') {
    return Status::InvalidArgument("the target is not a path");
  }
  const size_t q = target.find('?');
  WEAVER_RETURN_IF_ERROR(url_decode(target.substr(0, q), &r->path));
  if (q != std::string::npos) WEAVER_RETURN_IF_ERROR(parse_query(target.substr(q + 1), r));
  for (size_t at = line_end; at < head.size();) {
    size_t next = head.find("\r\n", at + 2);
    if (next == std::string::npos) next = head.size();
    const std::string h = head.substr(at + 2, next - at - 2);
    const size_t colon = h.find(':');
    if (colon == std::string::npos || colon == 0) {
      return Status::InvalidArgument("malformed header line");
    }
    size_t v = colon + 1;
    while (v < h.size() && (h[v] == ' ' || h[v] == '\t')) ++v;
    r->headers[lower(h.substr(0, colon))] = h.substr(v);
    at = next;
  }
  const auto c = r->headers.find("connection");
  const std::string connection = c == r->headers.end() ? "" : lower(c->second);
  r->keep_alive = version == "HTTP/1.1" ? connection != "close" : connection == "keep-alive";
  return Status::Ok();
}

Status Server::listen(const ServerOptions& o) {
  o_ = o;
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(uint16_t(o.port));
  if (::inet_pton(AF_INET, o.bind.c_str(), &addr.sin_addr) != 1) {
    return Status::InvalidArgument("--bind '" + o.bind + "' is not an IPv4 address");
  }
  // Non-blocking: the threads that poll() woke for one connection and lost
  // it to another go back to polling instead of waiting in accept().
  listen_fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
  if (listen_fd_ < 0) return Status::IOError(std::string("socket: ") + std::strerror(errno));
  const int one = 1;
  ::setsockopt(listen_fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
  if (::bind(listen_fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0 ||
      ::listen(listen_fd_, 128) != 0) {
    return Status::IOError(o.bind + ":" + std::to_string(o.port) + ": " + std::strerror(errno));
  }
  socklen_t len = sizeof addr;
  ::getsockname(listen_fd_, reinterpret_cast<sockaddr*>(&addr), &len);
  port_ = ntohs(addr.sin_port);
  return Status::Ok();
}

Server::~Server() {
  if (listen_fd_ >= 0) ::close(listen_fd_);
}

void Server::serve(const Handler& handler, const std::function<void()>& on_start) {
  std::vector<std::thread> pool;
  for (int i = 0; i < o_.threads; ++i) pool.emplace_back([&] { worker(handler, on_start); });
  for (auto& t : pool) t.join();
}

void Server::worker(const Handler& handler, const std::function<void()>& on_start) {
  if (on_start) on_start();
  while (!stopping_) {
    // Wait a little at a time, so that stop() is noticed.
    pollfd p{listen_fd_, POLLIN, 0};
    if (::poll(&p, 1, 200) <= 0) continue;
    const int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC);  // a blocking socket
    if (fd < 0) continue;  // another thread took it, or the client left
    timeval tv{o_.timeout_ms / 1000, (o_.timeout_ms % 1000) * 1000};
    ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    ::setsockopt(fd, SOL_SOCKET, SO_SNDTIMEO, &tv, sizeof tv);
    const int one = 1;  // answers go out whole, at once
    ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    answer(fd, handler);
    ::close(fd);
  }
}

void Server::answer(int fd, const Handler& handler) {
  Reader in(fd, o_.timeout_ms, stopping_);
  for (int served = 0; served < o_.max_requests && !stopping_; ++served) {
    // Between two requests a client may idle only a little: the thread is
    // what the next connection waits for.
    if (served > 0 && !in.pending()) {
      pollfd p{fd, POLLIN, 0};
      if (::poll(&p, 1, o_.idle_ms) <= 0) return;
    }
    std::string head;
    int status = 0;
    if (!in.head(&head, &status)) {
      if (status != 0) respond(fd, error_response(status, reason(status)), false);
      return;
    }
    Request r;
    bool too_large = false;
    Status st = parse_request_head(head, &r, &too_large);
    if (!st.ok())
      return (void)respond(fd, error_response(too_large ? 431 : 400, st.message()), false);
    uint64_t length = 0;
    const auto cl = r.headers.find("content-length");
    if (cl != r.headers.end()) {
      char* end = nullptr;
      length = std::strtoull(cl->second.c_str(), &end, 10);
      if (cl->second.empty() || *end != '\0' || !std::isdigit(uint8_t(cl->second[0]))) {
        return (void)respond(fd, error_response(400, "bad Content-Length"), false);
      }
    }
    if (r.headers.count("transfer-encoding")) {
      return (void)respond(
          fd, error_response(400, "chunked bodies are not taken: send Content-Length"), false);
    }
    if (length > o_.max_body) {
      return (void)respond(fd,
                           error_response(413, "the body is larger than " +
                                                   std::to_string(o_.max_body >> 20) + " MiB"),
                           false);
    }
    if (!in.body(length, &r.body)) {
      return (void)respond(fd, error_response(408, "the body did not arrive"), false);
    }
    const bool keep = r.keep_alive && served + 1 < o_.max_requests && !stopping_;
    if (!respond(fd, handler(r), keep) || !keep) return;
  }
}

}  // namespace weaver::serve
