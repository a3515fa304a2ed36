// serve/http: the request parser's rules, and the server's pool of threads
// answering many clients at once on 127.0.0.1 (bounded in count and time;
// the ServeThreads tests also run under ThreadSanitizer).
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <future>
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
  ASSERT_NE(r.header("content-length"), nullptr);
  EXPECT_EQ(*r.header("content-length"), "12");
  EXPECT_TRUE(r.keep_alive);
  ASSERT_TRUE(parse("GET / HTTP/1.1\r\nHost: h\r\nConnection: Close", &r).ok());
  EXPECT_FALSE(r.keep_alive);
  ASSERT_TRUE(parse("GET / HTTP/1.0", &r).ok());
  EXPECT_FALSE(r.keep_alive);
  ASSERT_TRUE(parse("GET / HTTP/1.0\r\nConnection: keep-alive", &r).ok());
  EXPECT_TRUE(r.keep_alive);
  ASSERT_TRUE(parse("GET /a%20b+c HTTP/1.1\r\nHost: h", &r).ok());
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
  EXPECT_TRUE(
      parse("GET /" + std::string(kMaxRequestLine - 15, 'a') + " HTTP/1.1\r\nHost: h", &r).ok());
  EXPECT_FALSE(parse("GET /" + std::string(kMaxRequestLine, 'a') + " HTTP/1.1", &r, &large).ok());
  EXPECT_TRUE(large);
  EXPECT_FALSE(parse("GET / HTTP/1.1\r\nX: " + std::string(kMaxHeaders, 'y'), &r, &large).ok());
  EXPECT_TRUE(large);
}

// RFC 9112's framing rules: what a proxy in front could read otherwise is
// refused, not repaired (request smuggling).
TEST(ServeHttp, RefusesWhatAProxyCouldReadOtherwise) {
  Request r;
  for (const char* bad : {
           "GET / HTTP/1.1\r\nHost: h\r\nContent-Length : 36",  // space before the colon
           "GET / HTTP/1.1\r\nHost: h\r\nContent-Length\t: 36",
           "GET / HTTP/1.1\r\nHost: h\r\nX: a\r\n folded",  // obs-fold
           "GET / HTTP/1.1\r\nHost: h\r\nX: a\rb",          // CR inside a value
           "GET / HTTP/1.1\r\nHost: h\r\nX: a\nb",
           "GET / HTTP/1.1",                        // no Host
           "GET / HTTP/1.1\r\nHost: a\r\nHost: b",  // two Hosts
           "GET / HTTP/1.1\r\nHost: h\r\nX(y): 1",  // a name that is no token
       }) {
    EXPECT_FALSE(parse(bad, &r).ok()) << bad;
  }
  std::string nul = "GET / HTTP/1.1\r\nHost: h\r\nX: a";
  nul += '\0';
  EXPECT_FALSE(parse(nul + "b", &r).ok());
  // A NUL in a header's name (found by fuzz/http_request_fuzz.cc).
  EXPECT_FALSE(parse(std::string("GET / HTTP/1.1\r\nHost: h\r\nCo\0\0: x", 32), &r).ok());
  ASSERT_TRUE(parse("GET / HTTP/1.0", &r).ok());  // HTTP/1.0 needs no Host
  EXPECT_TRUE(r.http10);
  // Repeated headers are kept, in order.
  ASSERT_TRUE(parse("GET / HTTP/1.1\r\nHost: h\r\nX: 1\r\nX: 2 \t", &r).ok());
  EXPECT_EQ(r.header_count("x"), 2u);
  EXPECT_EQ(r.headers.back().second, "2");
  // Connection is a list of tokens.
  ASSERT_TRUE(parse("GET / HTTP/1.1\r\nHost: h\r\nConnection: Upgrade, CLOSE", &r).ok());
  EXPECT_FALSE(r.keep_alive);
  ASSERT_TRUE(parse("GET / HTTP/1.1\r\nHost: h\r\nConnection: closed", &r).ok());
  EXPECT_TRUE(r.keep_alive);
  ASSERT_TRUE(parse("GET / HTTP/1.0\r\nConnection: foo, Keep-Alive", &r).ok());
  EXPECT_TRUE(r.keep_alive);
  // Content-Length: the same twice is one length; two that differ, a list,
  // a sign or any Transfer-Encoding is a 400.
  uint64_t length = 0;
  Response error;
  ASSERT_TRUE(
      parse("POST / HTTP/1.1\r\nHost: h\r\nContent-Length: 7\r\ncontent-length: 7", &r).ok());
  EXPECT_TRUE(body_length(r, 100, &length, &error));
  EXPECT_EQ(length, 7u);
  for (const char* bad :
       {"Content-Length: 7\r\nContent-Length: 8", "Content-Length: 7, 7", "Content-Length: +7",
        "Transfer-Encoding: chunked", "Transfer-Encoding: identity\r\nContent-Length: 7"}) {
    ASSERT_TRUE(parse(std::string("POST / HTTP/1.1\r\nHost: h\r\n") + bad, &r).ok()) << bad;
    EXPECT_FALSE(body_length(r, 100, &length, &error)) << bad;
    EXPECT_EQ(error.status, 400) << bad;
  }
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
            ask(fd, "POST /c" + std::to_string(c) + " HTTP/1.1\r\nHost: h\r\nContent-Length: " +
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
  o.idle_ms = 60000;  // the idle client stays connected through the stop
  ASSERT_TRUE(server.listen(o).ok());
  std::promise<void> stopped;
  std::thread pool([&] {
    server.serve([](const Request&) { return Response(200); });
    stopped.set_value();
  });
  const int idle = connect_local(server.port());  // connected, never asking
  const int asking = connect_local(server.port());
  EXPECT_NE(ask(asking, "GET / HTTP/1.1\r\nHost: h\r\n\r\n").find("200 OK"), std::string::npos);
  for (int i = 0; i < 500 && server.connections() != 2; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ASSERT_EQ(server.connections(), 2);  // both clients are connected when it stops
  server.stop();
  // The pool ends within seconds (a hang fails here, not at the suite's timeout).
  const bool ended =
      stopped.get_future().wait_for(std::chrono::seconds(10)) == std::future_status::ready;
  if (!ended) std::abort();
  pool.join();
  ::close(idle);
  ::close(asking);
}

// A server on its own thread for one test, stopped at the end.
class Running {
 public:
  explicit Running(
      ServerOptions o,
      Server::Handler h = [](const Request& r) { return Response(200, "text/plain", r.path); }) {
    o.port = 0;
    EXPECT_TRUE(server_.listen(o).ok());
    thread_ = std::thread([this, h] { server_.serve(h); });
  }
  ~Running() {
    server_.stop();
    thread_.join();
  }
  Server& server() { return server_; }
  int connect() { return connect_local(server_.port()); }

 private:
  Server server_;
  std::thread thread_;
};

// The open descriptors of this process.
int open_descriptors() {
  int n = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator("/proc/self/fd")) ++n;
  return n;
}

// Waits (at most 5 s, in 10 ms steps) until the server holds n connections.
bool wait_for_connections(Server& s, int n) {
  for (int i = 0; i < 500 && s.connections() != n; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return s.connections() == n;
}

// Slow clients hold a connection each, never a thread: with one worker and
// ten clients halfway through their requests, another client is answered
// before any of them finishes, and then each of them is answered too.
TEST(ServeThreads, SlowClientsDoNotHoldUpOthers) {
  ServerOptions o;
  o.threads = 1;
  o.timeout_ms = 60000;  // the old thread-per-connection server would wait this long
  Running run(o);
  std::vector<int> slow;
  for (int i = 0; i < 10; ++i) {
    slow.push_back(run.connect());
    ASSERT_GE(slow.back(), 0);
    const std::string part = "GET /slow" + std::to_string(i) + " HTTP/1.1\r\nHost:";
    ASSERT_EQ(::send(slow.back(), part.data(), part.size(), MSG_NOSIGNAL), ssize_t(part.size()));
  }
  ASSERT_TRUE(wait_for_connections(run.server(), 10));
  const int fast = run.connect();
  EXPECT_NE(ask(fast, "GET /fast HTTP/1.1\r\nHost: h\r\n\r\n").find("\r\n\r\n/fast"),
            std::string::npos);
  for (int i = 0; i < 10; ++i) {
    EXPECT_NE(ask(slow[i], " x\r\n\r\n").find("\r\n\r\n/slow" + std::to_string(i)),
              std::string::npos);
    ::close(slow[i]);
  }
  ::close(fast);
  EXPECT_TRUE(wait_for_connections(run.server(), 0));
}

// A request that does not arrive in time is answered 408 and closed.
TEST(ServeThreads, ARequestTooSlowToArriveGets408) {
  ServerOptions o;
  o.timeout_ms = 200;
  Running run(o);
  const int fd = run.connect();
  const std::string part = "GET / HTTP/1.1\r\nHost: h\r\n";
  ASSERT_EQ(::send(fd, part.data(), part.size(), MSG_NOSIGNAL), ssize_t(part.size()));
  char buf[512];
  const ssize_t n = ::recv(fd, buf, sizeof buf, 0);  // waits for the server's answer
  ASSERT_GT(n, 0);
  EXPECT_EQ(std::string(buf, size_t(n)).rfind("HTTP/1.1 408 ", 0), 0u);
  ::close(fd);
  EXPECT_TRUE(wait_for_connections(run.server(), 0));
}

// Past max_connections a new connection is answered 503 and closed; once
// others close, new ones are served again.  No descriptor is left open.
TEST(ServeThreads, ConnectionsPastTheLimitGet503AndNoneLeaks) {
  const int before = open_descriptors();
  {
    ServerOptions o;
    o.max_connections = 8;
    Running run(o);
    std::vector<int> held;
    for (int i = 0; i < 8; ++i) held.push_back(run.connect());
    ASSERT_TRUE(wait_for_connections(run.server(), 8));
    const int extra = run.connect();
    EXPECT_NE(ask(extra, "GET / HTTP/1.1\r\nHost: h\r\n\r\n").find(" 503 "), std::string::npos);
    ::close(extra);
    for (int fd : held) ::close(fd);
    ASSERT_TRUE(wait_for_connections(run.server(), 0));
    const int again = run.connect();
    EXPECT_NE(ask(again, "GET /again HTTP/1.1\r\nHost: h\r\n\r\n").find(" 200 "),
              std::string::npos);
    ::close(again);
    EXPECT_TRUE(wait_for_connections(run.server(), 0));
  }
  EXPECT_EQ(open_descriptors(), before);
}

// A server whose bodies held at once are at most 1000 bytes, answering
// each request with its body.
ServerOptions bodies_of_1000() {
  ServerOptions o;
  o.max_buffered = 1000;
  return o;
}
Response echo_body(const Request& r) { return Response(200, "text/plain", r.body); }

// Starts a body of 800 bytes on fd (3 of them sent) and waits until the
// server holds it.
void hold_800(Running& run, int fd) {
  const std::string head = "POST / HTTP/1.1\r\nHost: h\r\nContent-Length: 800\r\n\r\nabc";
  ASSERT_EQ(::send(fd, head.data(), head.size(), MSG_NOSIGNAL), ssize_t(head.size()));
  for (int i = 0; i < 500 && run.server().held_bytes() == 0; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ASSERT_EQ(run.server().held_bytes(), 800u);
}

// Bodies still arriving count against max_buffered: a second one that
// would pass it is refused (503) while the first is taken whole.
TEST(ServeThreads, BodiesHeldAtOnceAreBounded) {
  Running run(bodies_of_1000(), echo_body);
  const int first = run.connect(), second = run.connect();
  const std::string head = "POST / HTTP/1.1\r\nHost: h\r\nContent-Length: 800\r\n\r\n";
  ASSERT_NO_FATAL_FAILURE(hold_800(run, first));
  EXPECT_NE(ask(second, head + "x").find(" 503 "), std::string::npos);
  const std::string got = ask(first, std::string(797, 'y'));
  EXPECT_NE(got.find("\r\n\r\nabc" + std::string(797, 'y')), std::string::npos);
  ::close(first);
  ::close(second);
}

// Everything the server sends on fd until it closes the connection (or
// for 20 s at most).
std::string read_to_close(int fd) {
  timeval tv{20, 0};
  ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  std::string got;
  char buf[1 << 16];
  for (ssize_t n; (n = ::recv(fd, buf, sizeof buf, 0)) > 0;) got.append(buf, size_t(n));
  return got;
}

// The body of a chunked answer (after its head); *whole: it ended with the
// last chunk.
std::string dechunk(const std::string& body, bool* whole) {
  std::string out;
  *whole = false;
  for (size_t at = 0;;) {
    const size_t eol = body.find("\r\n", at);
    if (eol == std::string::npos) return out;
    const size_t n = std::stoul(body.substr(at, eol - at), nullptr, 16);
    if (n == 0) return *whole = body.compare(eol, 4, "\r\n\r\n") == 0, out;
    if (body.size() < eol + 2 + n + 2) return out;
    out.append(body, eol + 2, n);
    at = eol + 2 + n + 2;
  }
}

// A client refused while it still sends its body (the bodies held at once
// are at their limit) sends it all and reads the 503: the server drops the
// rest of the body rather than closing on it, which would reset the
// connection under the sender.
TEST(ServeThreads, ARefusedClientStillSendingItsBodyReadsTheRefusal) {
  Running run(bodies_of_1000(), echo_body);
  const int first = run.connect(), second = run.connect();
  ASSERT_NO_FATAL_FAILURE(hold_800(run, first));
  const std::string body(4 << 20, 'z');
  const std::string request =
      "POST / HTTP/1.1\r\nHost: h\r\nContent-Length: " + std::to_string(body.size()) + "\r\n\r\n" +
      body;
  // As most clients do (Python's http.client among them): the whole body
  // first, then the answer.  Closed at once, the connection would be reset
  // under the sender, which fails before it reads anything.
  size_t sent = 0;
  for (ssize_t n; sent < request.size() && (n = ::send(second, request.data() + sent,
                                                       request.size() - sent, MSG_NOSIGNAL)) > 0;) {
    sent += size_t(n);
  }
  EXPECT_EQ(sent, request.size()) << std::strerror(errno);
  const std::string got = read_to_close(second);
  EXPECT_EQ(got.rfind("HTTP/1.1 503 ", 0), 0u) << got.substr(0, 200);
  EXPECT_NE(got.find("too many request bodies"), std::string::npos);
  ::close(first);
  ::close(second);
}

// A streamed answer within kStreamHold goes out whole with its length; a
// longer one in chunks, whole, and the connection takes the next request;
// one that fails after its first chunks is cut short (no last chunk) and
// its connection closed.
TEST(ServeThreads, LongAnswersAreStreamedInChunks) {
  const auto pattern = [](size_t i) { return char('a' + (i * 7 + i / 1000) % 26); };
  Running run(ServerOptions{}, [&](const Request& r) {
    const size_t n = r.path == "/short" ? 100 : (3 << 20) + 5;
    const bool broken = r.path == "/broken";
    Response res(200, "text/plain");
    res.stream = [n, broken, &pattern](BodySink& sink) {
      std::string piece;
      for (size_t i = 0; i < n; i += piece.size()) {
        piece.clear();
        for (size_t k = i; k < std::min(n, i + 10000); ++k) piece += pattern(k);
        if (broken && i > (2 << 20)) return error_response(500, "broken");
        if (!sink.write(piece.data(), piece.size())) return error_response(500, "gone");
      }
      return Response(200);
    };
    return res;
  });
  std::string want;
  for (size_t k = 0; k < (3 << 20) + 5; ++k) want += pattern(k);

  int fd = run.connect();
  const std::string short_answer = ask(fd, "GET /short HTTP/1.1\r\nHost: h\r\n\r\n");
  EXPECT_NE(short_answer.find("Content-Length: 100\r\n"), std::string::npos) << short_answer;
  EXPECT_EQ(short_answer.substr(short_answer.find("\r\n\r\n") + 4), want.substr(0, 100));
  // The long one on the same connection, then a last request on it.
  const std::string req =
      "GET /long HTTP/1.1\r\nHost: h\r\n\r\nGET /short HTTP/1.1\r\nHost: h\r\nConnection: "
      "close\r\n\r\n";
  ASSERT_EQ(::send(fd, req.data(), req.size(), MSG_NOSIGNAL), ssize_t(req.size()));
  const std::string both = read_to_close(fd);
  ::close(fd);
  const size_t head = both.find("\r\n\r\n");
  ASSERT_NE(head, std::string::npos);
  EXPECT_NE(both.substr(0, head).find("Transfer-Encoding: chunked"), std::string::npos);
  EXPECT_EQ(both.substr(0, head).find("Content-Length"), std::string::npos);
  bool whole = false;
  const size_t next = both.find("HTTP/1.1 200", head);
  ASSERT_NE(next, std::string::npos) << "no answer after the chunked one";
  EXPECT_EQ(dechunk(both.substr(head + 4, next - head - 4), &whole), want);
  EXPECT_TRUE(whole);
  EXPECT_EQ(both.substr(both.size() - 100), want.substr(0, 100));

  fd = run.connect();
  const std::string broken_req = "GET /broken HTTP/1.1\r\nHost: h\r\n\r\n";
  ASSERT_EQ(::send(fd, broken_req.data(), broken_req.size(), MSG_NOSIGNAL),
            ssize_t(broken_req.size()));
  const std::string cut = read_to_close(fd);  // returns: the server closed it
  ::close(fd);
  const size_t cut_head = cut.find("\r\n\r\n");
  ASSERT_NE(cut_head, std::string::npos);
  EXPECT_EQ(cut.rfind("HTTP/1.1 200 OK", 0), 0u);
  const std::string got = dechunk(cut.substr(cut_head + 4), &whole);
  EXPECT_FALSE(whole);
  EXPECT_GT(got.size(), size_t{1} << 20);
  EXPECT_EQ(got, want.substr(0, got.size()));
}

// A client that asks to be asked for its body (Expect: 100-continue) is
// asked at once, then answered.
TEST(ServeThreads, ExpectContinueIsAskedForTheBody) {
  Running run(ServerOptions{},
              [](const Request& r) { return Response(200, "text/plain", r.body); });
  const int fd = run.connect();
  const std::string head =
      "POST / HTTP/1.1\r\nHost: h\r\nContent-Length: 5\r\nExpect: 100-continue\r\n\r\n";
  ASSERT_EQ(::send(fd, head.data(), head.size(), MSG_NOSIGNAL), ssize_t(head.size()));
  timeval tv{5, 0};
  ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  char buf[64];
  const ssize_t n = ::recv(fd, buf, sizeof buf, 0);
  ASSERT_GT(n, 0);
  EXPECT_EQ(std::string(buf, size_t(n)), "HTTP/1.1 100 Continue\r\n\r\n");
  const std::string answer = ask(fd, "hello");
  EXPECT_NE(answer.find("200 OK"), std::string::npos);
  EXPECT_EQ(answer.substr(answer.size() - 5), "hello");
  ::close(fd);
}

// HEAD is answered with GET's head and no body; an HTTP/1.0 client gets a
// long answer delimited by the connection's close, never chunked; blank
// lines before a request are skipped; a handler that throws is a 500 and
// the server goes on.
TEST(ServeThreads, HeadHttp10BlankLinesAndAThrowingHandler) {
  Running run(ServerOptions{}, [](const Request& r) {
    if (r.path == "/throw") throw std::bad_alloc();
    Response res(200, "text/plain", r.path == "/long" ? "" : "five!");
    if (r.path == "/long") {
      res.stream = [](BodySink& sink) {
        const std::string piece(100000, 'w');
        for (int i = 0; i < 30; ++i) {
          if (!sink.write(piece.data(), piece.size())) return error_response(500, "gone");
        }
        return Response(200);
      };
    }
    return res;
  });
  int fd = run.connect();
  const std::string req = "\r\n\r\nHEAD /x HTTP/1.1\r\nHost: h\r\n\r\n";
  ASSERT_EQ(::send(fd, req.data(), req.size(), MSG_NOSIGNAL), ssize_t(req.size()));
  std::string head;  // read to the end of the head: a HEAD answer has no body
  char buf[512];
  for (ssize_t n;
       head.find("\r\n\r\n") == std::string::npos && (n = ::recv(fd, buf, sizeof buf, 0)) > 0;) {
    head.append(buf, size_t(n));
  }
  EXPECT_EQ(head.rfind("HTTP/1.1 200", 0), 0u) << head;
  EXPECT_NE(head.find("Content-Length: 5\r\n"), std::string::npos);
  EXPECT_EQ(head.substr(head.find("\r\n\r\n") + 4), "");  // no body: the next answer follows
  const std::string thrown = ask(fd, "GET /throw HTTP/1.1\r\nHost: h\r\n\r\n");
  EXPECT_EQ(thrown.rfind("HTTP/1.1 500", 0), 0u) << thrown;
  const std::string after = ask(fd, "GET /x HTTP/1.1\r\nHost: h\r\n\r\n");
  EXPECT_EQ(after.substr(after.size() - 5), "five!");
  ::close(fd);
  fd = run.connect();
  const std::string old = "GET /long HTTP/1.0\r\n\r\n";
  ASSERT_EQ(::send(fd, old.data(), old.size(), MSG_NOSIGNAL), ssize_t(old.size()));
  const std::string got = read_to_close(fd);
  ::close(fd);
  const size_t end = got.find("\r\n\r\n");
  ASSERT_NE(end, std::string::npos);
  EXPECT_EQ(got.substr(0, end).find("chunked"), std::string::npos) << got.substr(0, end);
  EXPECT_EQ(got.substr(end + 4), std::string(3000000, 'w'));
}

// A client that reads a long answer slowly holds no worker: with one
// worker and four clients each taking 2 KB a second of a 20 MB answer,
// other requests are answered at once while all four are still
// connected.
TEST(ServeThreads, SlowReadersHoldNoWorker) {
  ServerOptions o;
  o.threads = 1;
  o.scratch_dir = ::testing::TempDir();
  Running run(o, [](const Request& r) {
    Response res(200, "text/plain", "quick");
    if (r.path == "/long") {
      res.stream = [](BodySink& sink) {
        const std::string piece(1 << 20, 'l');
        for (int i = 0; i < 20; ++i) {
          if (!sink.write(piece.data(), piece.size())) return error_response(500, "gone");
        }
        return Response(200);
      };
    }
    return res;
  });
  std::vector<int> slow;
  for (int i = 0; i < 4; ++i) {
    slow.push_back(run.connect());
    const int small = 4096;
    ::setsockopt(slow.back(), SOL_SOCKET, SO_RCVBUF, &small, sizeof small);
    const std::string req = "GET /long HTTP/1.1\r\nHost: h\r\n\r\n";
    ASSERT_EQ(::send(slow.back(), req.data(), req.size(), MSG_NOSIGNAL), ssize_t(req.size()));
  }
  char buf[2048];
  for (int round = 0; round < 3; ++round) {  // the slow clients read a little
    for (const int fd : slow) EXPECT_GT(::recv(fd, buf, sizeof buf, 0), 0);
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
  }
  // Answered while every slow reader is still connected: a server whose
  // worker they held would answer only once the send timeout dropped them.
  const int quick = run.connect();
  EXPECT_NE(ask(quick, "GET /q HTTP/1.1\r\nHost: h\r\n\r\n").find("quick"), std::string::npos);
  EXPECT_EQ(run.server().connections(), 5);
  ::close(quick);
  for (const int fd : slow) ::close(fd);
}

}  // namespace
}  // namespace weaver::serve
