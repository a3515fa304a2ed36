#include "serve/http.h"

#include <arpa/inet.h>
#include <netinet/in.h>
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

constexpr size_t kMaxHead = 16 << 10;

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

// Reads until the head ends ("\r\n\r\n"); what follows it is the start of
// the body.  False on timeout, close or a head too large (*status says).
bool read_head(int fd, std::string* head, std::string* rest, int* status) {
  char buf[4096];
  std::string got;
  for (;;) {
    const size_t end = got.find("\r\n\r\n");
    if (end != std::string::npos) {
      *head = got.substr(0, end);
      *rest = got.substr(end + 4);
      return true;
    }
    if (got.size() > kMaxHead) return *status = 431, false;
    const ssize_t n = ::recv(fd, buf, sizeof buf, 0);
    if (n <= 0) return *status = n < 0 && errno == EAGAIN ? 408 : 0, false;
    got.append(buf, size_t(n));
  }
}

std::string lower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// The request line and headers; false for a malformed head.
bool parse_head(const std::string& head, Request* r) {
  size_t at = head.find("\r\n");
  const std::string line = head.substr(0, at);
  const size_t sp1 = line.find(' '), sp2 = line.rfind(' ');
  if (sp1 == std::string::npos || sp2 <= sp1) return false;
  r->method = line.substr(0, sp1);
  const std::string target = line.substr(sp1 + 1, sp2 - sp1 - 1);
  if (line.compare(sp2 + 1, 5, "HTTP/") != 0 || target.empty() || target[0] != '/') return false;
  const size_t q = target.find('?');
  if (!url_decode(target.substr(0, q), &r->path).ok()) return false;
  if (q != std::string::npos) {
    const std::string qs = target.substr(q + 1);
    for (size_t from = 0; from <= qs.size();) {
      size_t amp = qs.find('&', from);
      if (amp == std::string::npos) amp = qs.size();
      const std::string pair = qs.substr(from, amp - from);
      const size_t eq = pair.find('=');
      std::string k, v;
      if (!url_decode(pair.substr(0, eq), &k).ok()) return false;
      if (eq != std::string::npos && !url_decode(pair.substr(eq + 1), &v).ok()) return false;
      if (!k.empty()) r->query[k] = v;
      from = amp + 1;
    }
  }
  while (at != std::string::npos) {
    const size_t next = head.find("\r\n", at + 2);
    const std::string h = head.substr(at + 2, next == std::string::npos ? next : next - at - 2);
    const size_t colon = h.find(':');
    if (colon == std::string::npos) return false;
    size_t v = colon + 1;
    while (v < h.size() && (h[v] == ' ' || h[v] == '\t')) ++v;
    r->headers[lower(h.substr(0, colon))] = h.substr(v);
    at = next;
  }
  return true;
}

bool send_all(int fd, const std::string& data) {
  for (size_t sent = 0; sent < data.size();) {
    const ssize_t n = ::send(fd, data.data() + sent, data.size() - sent, MSG_NOSIGNAL);
    if (n <= 0) return false;
    sent += size_t(n);
  }
  return true;
}

void respond(int fd, const Response& r) {
  std::string head = "HTTP/1.1 " + std::to_string(r.status) + " " + reason(r.status) + "\r\n";
  head += "Content-Type: " + r.content_type + "\r\n";
  head += "Content-Length: " + std::to_string(r.body.size()) + "\r\n";
  head += "Cache-Control: " + r.cache_control + "\r\n";
  head += "X-Content-Type-Options: nosniff\r\nConnection: close\r\n\r\n";
  if (send_all(fd, head)) send_all(fd, r.body);
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

void Server::serve(const Handler& handler) {
  std::vector<std::thread> pool;
  for (int i = 0; i < o_.threads; ++i) pool.emplace_back([&] { worker(handler); });
  for (auto& t : pool) t.join();
}

void Server::worker(const Handler& handler) {
  while (!stopping_) {
    // Wait a little at a time, so that stop() is noticed.
    pollfd p{listen_fd_, POLLIN, 0};
    if (::poll(&p, 1, 200) <= 0) continue;
    const int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC);  // a blocking socket
    if (fd < 0) continue;  // another thread took it, or the client left
    timeval tv{o_.timeout_ms / 1000, (o_.timeout_ms % 1000) * 1000};
    ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    ::setsockopt(fd, SOL_SOCKET, SO_SNDTIMEO, &tv, sizeof tv);
    answer(fd, handler);
    ::close(fd);
  }
}

void Server::answer(int fd, const Handler& handler) {
  std::string head, body;
  int status = 0;
  if (!read_head(fd, &head, &body, &status)) {
    if (status != 0) respond(fd, error_response(status, reason(status)));
    return;
  }
  Request r;
  if (!parse_head(head, &r)) return respond(fd, error_response(400, "malformed request"));
  uint64_t length = 0;
  const auto cl = r.headers.find("content-length");
  if (cl != r.headers.end()) {
    char* end = nullptr;
    length = std::strtoull(cl->second.c_str(), &end, 10);
    if (cl->second.empty() || *end != '\0') {
      return respond(fd, error_response(400, "bad Content-Length"));
    }
  }
  if (r.headers.count("transfer-encoding")) {
    return respond(fd, error_response(400, "chunked bodies are not taken: send Content-Length"));
  }
  if (length > o_.max_body) {
    return respond(fd, error_response(413, "the body is larger than " +
                                               std::to_string(o_.max_body >> 20) + " MiB"));
  }
  char buf[1 << 16];
  while (body.size() < length) {
    const ssize_t n = ::recv(fd, buf, sizeof buf, 0);
    if (n <= 0) return respond(fd, error_response(408, "the body did not arrive"));
    body.append(buf, size_t(n));
  }
  body.resize(length);
  r.body = std::move(body);
  respond(fd, handler(r));
}

}  // namespace weaver::serve
