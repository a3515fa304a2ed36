// serve/http: the request parser's rules, and the server's pool of threads
// answering many clients at once on 127.0.0.1 (bounded in count and time;
// the ServeThreads tests also run under ThreadSanitizer).
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <string>
#include <thread>
#include <vector>

#include "serve/http.h"

namespace weaver::serve {
namespace {

Status parse(const std::string& head, Request* r, bool* too_large = nullptr) {
  bool large = false;
  const Status st = parse_request_head(head, r, &large);
  if (too_large != nullptr) *too_large = large;
  return st;
}

TEST(ServeHttp, ParsesTheRequestLineTargetAndHeaders) {
  Request r;
  ASSERT_TRUE(parse("GET /api/locate?x=1.5&y=%32&units=m&flag HTTP/1.1\r\n"
                    "Host: 127.0.0.1\r\nCONTENT-length:  12",
                    &r)
                  .ok());
  EXPECT_EQ(r.method, "GET");
  EXPECT_EQ(r.path, "/api/locate");
  EXPECT_EQ(r.query.at("x"), "1.5");
  EXPECT_EQ(r.query.at("y"), "2");
  EXPECT_EQ(r.query.at("units"), "m");
  EXPECT_EQ(r.query.at("flag"), "");
  EXPECT_EQ(r.headers.at("content-length"), "12");
  EXPECT_TRUE(r.keep_alive);
  ASSERT_TRUE(parse("GET / HTTP/1.1\r\nConnection: Close", &r).ok());
  EXPECT_FALSE(r.keep_alive);
  ASSERT_TRUE(parse("GET / HTTP/1.0", &r).ok());
  EXPECT_FALSE(r.keep_alive);
  ASSERT_TRUE(parse("GET / HTTP/1.0\r\nConnection: keep-alive", &r).ok());
  EXPECT_TRUE(r.keep_alive);
  ASSERT_TRUE(parse("GET /a%20b+c HTTP/1.1", &r).ok());
  EXPECT_EQ(r.path, "/a b c");
}

TEST(ServeHttp, RefusesMalformedHeadsAndKeepsToItsLimits) {
  Request r;
  bool large = false;
  for (const char* bad :
       {"", "GET", "GET /", " /api HTTP/1.1", "get / HTTP/1.1", "GET /a b HTTP/1.1",
        "GET api HTTP/1.1", "GET / HTTP/2.0", "GET /%zz HTTP/1.1", "GET /%4 HTTP/1.1",
        "GET / HTTP/1.1\r\nno colon", "GET / HTTP/1.1\r\n: empty name", "GET /\x01 HTTP/1.1"}) {
    EXPECT_FALSE(parse(bad, &r, &large).ok()) << bad;
    EXPECT_FALSE(large) << bad;
  }
  EXPECT_TRUE(parse("GET /" + std::string(kMaxRequestLine - 15, 'a') + " HTTP/1.1", &r).ok());
  EXPECT_FALSE(parse("GET /" + std::string(kMaxRequestLine, 'a') + " HTTP/1.1", &r, &large).ok());
  EXPECT_TRUE(large);
  EXPECT_FALSE(parse("GET / HTTP/1.1\r\nX: " + std::string(kMaxHeaders, 'y'), &r, &large).ok());
  EXPECT_TRUE(large);
}

int connect_local(int port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(uint16_t(port));
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
    ::close(fd);
    return -1;
  }
  return fd;
}

// One request on fd and its whole response, or "" when the connection fails.
std::string ask(int fd, const std::string& request) {
  if (::send(fd, request.data(), request.size(), MSG_NOSIGNAL) != ssize_t(request.size())) {
    return "";
  }
  std::string got;
  char buf[4096];
  for (;;) {
    const size_t head = got.find("\r\n\r\n");
    if (head != std::string::npos) {
      const size_t at = got.find("Content-Length: ");
      if (at != std::string::npos && got.size() >= head + 4 + std::stoul(got.substr(at + 16))) {
        return got;
      }
    }
    const ssize_t n = ::recv(fd, buf, sizeof buf, 0);
    if (n <= 0) return "";
    got.append(buf, size_t(n));
  }
}

TEST(ServeThreads, ManyKeptAliveClientsGetTheirOwnAnswers) {
  Server server;
  ServerOptions o;
  o.port = 0;
  o.threads = 3;
  ASSERT_TRUE(server.listen(o).ok());
  std::atomic<int> handled{0};
  std::thread pool([&] {
    server.serve([&](const Request& r) {
      ++handled;
      // Echo what was asked: a wrong pairing of request and answer shows.
      return Response(200, "text/plain", r.method + " " + r.path + " " + r.body);
    });
  });
  constexpr int kClients = 6, kRequests = 200;
  std::atomic<int> right{0};
  std::vector<std::thread> clients;
  for (int c = 0; c < kClients; ++c) {
    clients.emplace_back([&, c] {
      // Three connections at a time are served, the others wait for one to
      // idle out: each client opens its own and makes its requests in turn.
      const int fd = connect_local(server.port());
      if (fd < 0) return;
      for (int i = 0; i < kRequests; ++i) {
        const std::string body = std::to_string(c) + "-" + std::to_string(i);
        const std::string got =
            ask(fd, "POST /c" + std::to_string(c) + " HTTP/1.1\r\nContent-Length: " +
                        std::to_string(body.size()) + "\r\n\r\n" + body);
        if (got.find("\r\n\r\nPOST /c" + std::to_string(c) + " " + body) != std::string::npos) {
          ++right;
        }
      }
      ::close(fd);
    });
  }
  for (auto& t : clients) t.join();
  server.stop();
  pool.join();
  EXPECT_EQ(right.load(), kClients * kRequests);
  EXPECT_EQ(handled.load(), kClients * kRequests);
}

TEST(ServeThreads, StopEndsThePoolWithClientsConnected) {
  Server server;
  ServerOptions o;
  o.port = 0;
  o.threads = 2;
  o.idle_ms = 50;
  ASSERT_TRUE(server.listen(o).ok());
  std::thread pool([&] { server.serve([](const Request&) { return Response(200); }); });
  const int idle = connect_local(server.port());  // connected, never asking
  const int asking = connect_local(server.port());
  EXPECT_NE(ask(asking, "GET / HTTP/1.1\r\n\r\n").find("200 OK"), std::string::npos);
  server.stop();
  pool.join();  // returns: the test would hang (and time out) otherwise
  ::close(idle);
  ::close(asking);
}

}  // namespace
}  // namespace weaver::serve
