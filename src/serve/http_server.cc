// The Server of serve/http.h: one polling thread that owns the connections
// while they wait for or receive a request, and a pool of workers that own
// a connection from a whole request until its answer is sent.
#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <strings.h>
#include <sys/socket.h>
#include <sys/uio.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <climits>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <deque>
#include <list>
#include <mutex>
#include <string_view>
#include <thread>
#include <vector>

#include "serve/http.h"

namespace weaver::serve {
namespace {

int64_t now_ms() {
  using namespace std::chrono;
  return duration_cast<milliseconds>(steady_clock::now().time_since_epoch()).count();
}

struct Connection {
  int fd = -1;
  std::string in;         // received, not yet taken as a request
  int64_t since = 0;      // when it went idle, or when its request began
  bool idle = true;       // between requests, with no byte of the next
  bool busy = false;      // a worker has it
  bool draining = false;  // refused: its answer sent, the rest of its bytes read and dropped
  int served = 0;         // requests answered
  uint64_t reserved = 0;  // body bytes counted against max_buffered
  Request request;        // the request a worker answers
};

// What a connection's bytes hold: a whole request (moved from c.in to
// c.request), not yet one (*length: the body it announces, when its head
// is in), or a mistake to answer (*refusal) before closing.
enum class Take { kRequest, kMore, kRefuse };
Take take_request(Connection& c, uint64_t max_body, uint64_t* length, Response* refusal,
                  bool* expects_continue = nullptr) {
  *length = 0;
  const size_t end = c.in.find("\r\n\r\n");
  if (end == std::string::npos) {
    if (c.in.size() <= kMaxRequestLine + kMaxHeaders) return Take::kMore;
    *refusal = error_response(431, "the request's head is longer than 40 KiB");
    return Take::kRefuse;
  }
  Request r;
  bool too_large = false;
  const Status st = parse_request_head(c.in.substr(0, end), &r, &too_large);
  if (!st.ok()) {
    *refusal = error_response(too_large ? 431 : 400, st.message());
    return Take::kRefuse;
  }
  if (!body_length(r, max_body, length, refusal)) return Take::kRefuse;
  if (c.in.size() < end + 4 + *length) {
    if (expects_continue != nullptr) {
      const auto e = r.headers.find("expect");
      *expects_continue =
          e != r.headers.end() && ::strcasecmp(e->second.c_str(), "100-continue") == 0;
    }
    c.in.reserve(end + 4 + *length);
    return Take::kMore;
  }
  if (c.in.size() == end + 4 + *length && *length > (64 << 10)) {
    // A large body that ends what arrived (the usual case): moved, not
    // copied, and the connection keeps no buffer of its size.
    r.body = std::move(c.in);
    r.body.erase(0, end + 4);
    c.in = std::string();
  } else {
    r.body.assign(c.in, end + 4, *length);
    c.in.erase(0, end + 4 + *length);
  }
  c.request = std::move(r);
  return Take::kRequest;
}

// After an answer, a worker waits a moment for the client's next request:
// one that comes at once (a client asking in a loop, pipelining) is
// answered without a trip through the polling thread.  True when c holds
// a whole request again; anything else goes back to the poller.
bool next_request_at_once(Connection& c, uint64_t max_body) {
  uint64_t length = 0;
  Response refusal;
  if (!c.in.empty()) return take_request(c, max_body, &length, &refusal) == Take::kRequest;
  pollfd p{c.fd, POLLIN, 0};
  if (::poll(&p, 1, 1) <= 0) return false;
  char chunk[1 << 14];
  const ssize_t n = ::recv(c.fd, chunk, sizeof chunk, 0);
  if (n <= 0) return false;  // the poller sees the close or the error
  c.in.append(chunk, size_t(n));
  return take_request(c, max_body, &length, &refusal) == Take::kRequest;
}

// Sends all of parts, in order, on a non-blocking socket (one sendmsg for
// all that fits: a head and a short body in two sends would wait on the
// client's delayed ACK), waiting for room at most timeout_ms in all; false
// if the client is gone or too slow.
bool send_parts(int fd, std::initializer_list<std::string_view> parts, int timeout_ms) {
  std::vector<iovec> left;
  for (const std::string_view p : parts) {
    if (!p.empty()) left.push_back({const_cast<char*>(p.data()), p.size()});
  }
  const int64_t deadline = now_ms() + timeout_ms;
  size_t first = 0;
  while (first < left.size()) {
    msghdr m{};
    m.msg_iov = &left[first];
    m.msg_iovlen = std::min<size_t>(left.size() - first, IOV_MAX);
    ssize_t sent = ::sendmsg(fd, &m, MSG_NOSIGNAL);
    if (sent < 0 && errno == EINTR) continue;
    if (sent < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
      const int64_t wait = deadline - now_ms();
      pollfd p{fd, POLLOUT, 0};
      if (wait <= 0 || ::poll(&p, 1, int(std::min<int64_t>(wait, 200))) < 0) return false;
      continue;
    }
    if (sent <= 0) return false;
    for (; first < left.size() && size_t(sent) >= left[first].iov_len; ++first) {
      sent -= ssize_t(left[first].iov_len);
    }
    if (first < left.size()) {
      left[first].iov_base = static_cast<char*>(left[first].iov_base) + sent;
      left[first].iov_len -= size_t(sent);
    }
  }
  return true;
}

bool send_whole(int fd, const Response& r, bool keep_alive, int timeout_ms) {
  return send_parts(fd, {response_head(r, keep_alive), r.body}, timeout_ms);
}

// A streamed answer's sink on a connection: it holds the first
// kStreamHold bytes; past them it sends the head and then each write as a
// chunk of its own (the stream's stdio buffer makes them 256 KiB).
class SocketSink : public BodySink {
 public:
  SocketSink(int fd, const Response& head, bool keep_alive, int timeout_ms)
      : fd_(fd), head_(head), keep_(keep_alive), timeout_ms_(timeout_ms) {}

  bool write(const char* data, size_t n) override {
    if (failed_) return false;
    if (!started_ && held_.size() + n <= kStreamHold) return held_.append(data, n), true;
    if (!started_) {
      started_ = true;
      failed_ = !send_chunk(response_head(head_, keep_, true), held_);
      held_ = std::string();
    }
    failed_ = failed_ || !send_chunk("", std::string_view(data, n));
    return !failed_;
  }

  // Ends the answer as the stream said (end): true if the connection may
  // take another request.
  bool finish(Response end) {
    if (!started_) {
      if (end.status != 200) return send_whole(fd_, end, keep_, timeout_ms_) && keep_;
      Response whole = head_;
      whole.stream = nullptr;
      whole.body = std::move(held_);
      return send_whole(fd_, whole, keep_, timeout_ms_) && keep_;
    }
    if (failed_ || end.status != 200) return false;  // cut short: the client sees it
    return send_parts(fd_, {"0\r\n\r\n"}, timeout_ms_) && keep_;
  }

 private:
  // Sends `before` (the head, before the first chunk), then data as a chunk.
  bool send_chunk(std::string_view before, std::string_view data) {
    if (data.empty()) return send_parts(fd_, {before}, timeout_ms_);
    char size[24];
    const int len = std::snprintf(size, sizeof size, "%zx\r\n", data.size());
    return send_parts(fd_, {before, std::string_view(size, size_t(len)), data, "\r\n"},
                      timeout_ms_);
  }

  int fd_;
  const Response& head_;
  bool keep_;
  int timeout_ms_;
  bool started_ = false, failed_ = false;
  std::string held_;
};

// Sends r (running its stream, if it has one): true if the connection may
// take another request.
bool send_response(int fd, const Response& r, bool keep_alive, int timeout_ms) {
  if (!r.stream) return send_whole(fd, r, keep_alive, timeout_ms) && keep_alive;
  SocketSink sink(fd, r, keep_alive, timeout_ms);
  return sink.finish(r.stream(sink));
}

// How long a refused connection is read (and what it sends dropped) before
// it is closed (Poller::refuse).
constexpr int64_t kLingerMs = 1000;

// The work handed between the poller and the workers.
class Queues {
 public:
  void push_job(Connection* c) {
    std::lock_guard<std::mutex> l(m_);
    jobs_.push_back(c);
    ready_.notify_one();
  }
  // The next request to answer; null once the queue is closed and empty.
  Connection* pop_job() {
    std::unique_lock<std::mutex> l(m_);
    ready_.wait(l, [&] { return !jobs_.empty() || closed_; });
    if (jobs_.empty()) return nullptr;
    Connection* c = jobs_.front();
    jobs_.pop_front();
    return c;
  }
  void close() {
    std::lock_guard<std::mutex> l(m_);
    closed_ = true;
    ready_.notify_all();
  }
  // A worker is done with c: keep it open for its next request or not.
  void push_done(Connection* c, bool keep, int wake_fd) {
    {
      std::lock_guard<std::mutex> l(m_);
      done_.push_back({c, keep});
    }
    const char b = 1;
    (void)!::write(wake_fd, &b, 1);
  }
  std::vector<std::pair<Connection*, bool>> take_done() {
    std::lock_guard<std::mutex> l(m_);
    std::vector<std::pair<Connection*, bool>> out(done_.begin(), done_.end());
    done_.clear();
    return out;
  }

 private:
  std::mutex m_;
  std::condition_variable ready_;
  std::deque<Connection*> jobs_;
  std::deque<std::pair<Connection*, bool>> done_;
  bool closed_ = false;
};

// The polling thread's side: the open connections and what it does with
// their bytes.
class Poller {
 public:
  Poller(const ServerOptions& o, int listen_fd, Queues& q, std::atomic<int>& open,
         std::atomic<uint64_t>& buffered)
      : o_(o), listen_fd_(listen_fd), q_(q), open_(open), buffered_(buffered) {}
  ~Poller() {
    while (!conns_.empty()) close(conns_.begin());
  }
  void run(const std::atomic<bool>& stopping, int wake_fd);

 private:
  void accept_all();
  // Reads what c's client sent; false when it closed or failed.
  bool receive(Connection& c);
  // Takes the next whole request from c's bytes to a worker, if there is
  // one; false when c must close (an error was answered).
  bool dispatch(Connection& c);
  // Answers r and stops taking requests from c.  Its client may still be
  // sending a body: closing at once would reset the connection, and the
  // client would lose the answer unread.  So c stops writing and is read
  // (and what it sends dropped) until its client closes, for a second at
  // most: a lingering close, as web servers do.  True: c stays open.
  bool refuse(Connection& c, const Response& r) {
    send_response(c.fd, r, false, 100);
    ::shutdown(c.fd, SHUT_WR);
    buffered_ -= c.reserved;
    c.reserved = 0;
    c.in = std::string();
    c.draining = true;
    c.since = now_ms();
    return true;
  }
  void expire(int64_t now);
  void close(std::list<Connection>::iterator it) {
    buffered_ -= it->reserved;
    ::close(it->fd);
    --open_;
    conns_.erase(it);
  }

  const ServerOptions& o_;
  int listen_fd_;
  Queues& q_;
  std::atomic<int>& open_;
  std::list<Connection> conns_;      // stable addresses: workers hold pointers
  std::atomic<uint64_t>& buffered_;  // body bytes reserved by all connections
};

void Poller::run(const std::atomic<bool>& stopping, int wake_fd) {
  std::vector<pollfd> fds;
  std::vector<std::list<Connection>::iterator> polled;
  while (!stopping) {
    for (const auto& [c, keep] : q_.take_done()) {
      const auto it = std::find_if(conns_.begin(), conns_.end(),
                                   [c = c](const Connection& x) { return &x == c; });
      buffered_ -= it->reserved;
      it->reserved = 0, it->busy = false, it->idle = it->in.empty(), it->since = now_ms();
      if (!keep || (!it->in.empty() && !dispatch(*it))) close(it);
    }
    fds.assign({{wake_fd, POLLIN, 0}, {listen_fd_, POLLIN, 0}});
    polled.clear();
    for (auto it = conns_.begin(); it != conns_.end(); ++it) {
      if (!it->busy) fds.push_back({it->fd, POLLIN, 0}), polled.push_back(it);
    }
    if (::poll(fds.data(), fds.size(), 200) < 0 && errno != EINTR) break;
    if (fds[0].revents & POLLIN) {
      char buf[256];
      while (::read(wake_fd, buf, sizeof buf) > 0) {
      }
    }
    if (fds[1].revents & POLLIN) accept_all();
    for (size_t i = 0; i < polled.size(); ++i) {
      if (fds[i + 2].revents == 0) continue;
      Connection& c = *polled[i];
      if (!receive(c) || (!c.in.empty() && !dispatch(c))) close(polled[i]);
    }
    expire(now_ms());
  }
}

void Poller::accept_all() {
  for (;;) {
    const int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC | SOCK_NONBLOCK);
    if (fd < 0) return;  // none left (EAGAIN), or the client left
    const int one = 1;   // answers go out whole, at once
    ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    if (int(conns_.size()) >= o_.max_connections) {
      send_response(fd,
                    error_response(503, "too many connections (" +
                                            std::to_string(o_.max_connections) + "): retry"),
                    false, 100);
      ::close(fd);
      continue;
    }
    Connection c;
    c.fd = fd;
    c.since = now_ms();
    conns_.push_back(std::move(c));
    ++open_;
  }
}

bool Poller::receive(Connection& c) {
  char chunk[1 << 16];
  for (;;) {
    const ssize_t n = ::recv(c.fd, chunk, sizeof chunk, 0);
    if (n > 0 && c.draining) continue;  // dropped
    if (n > 0) {
      if (c.idle) c.idle = false, c.since = now_ms();  // a request begins
      c.in.append(chunk, size_t(n));
      // Past a head's limits (or the body it announced), dispatch looks
      // before more is read.
      if (c.in.size() > kMaxRequestLine + kMaxHeaders + 4 + c.reserved) return true;
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    return n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK);
  }
}

bool Poller::dispatch(Connection& c) {
  uint64_t length = 0;
  Response refusal;
  bool expects_continue = false;
  switch (take_request(c, o_.max_body, &length, &refusal, &expects_continue)) {
    case Take::kRefuse: return refuse(c, refusal);
    case Take::kMore:
      // A body still coming counts against the bytes held at once.
      if (c.reserved == 0 && length > 0) {
        if (buffered_ + length > o_.max_buffered) {
          return refuse(c, error_response(503, "too many request bodies at once: retry"));
        }
        c.reserved = length, buffered_ += length;
        // A client that waits to be asked for its body (curl does, past
        // 1 MB) is asked now, rather than after its own timeout of a second.
        static constexpr char kContinue[] = "HTTP/1.1 100 Continue\r\n\r\n";
        if (expects_continue && !send_parts(c.fd, {kContinue}, 100)) {
          return false;
        }
      }
      return true;
    case Take::kRequest: break;
  }
  c.busy = true;
  q_.push_job(&c);
  return true;
}

// Closes the connections idle too long, and answers 408 to those whose
// request takes too long to arrive.
void Poller::expire(int64_t now) {
  for (auto it = conns_.begin(); it != conns_.end();) {
    const auto next = std::next(it);
    if (it->draining) {
      if (now - it->since > kLingerMs) close(it);
    } else if (!it->busy && it->idle && now - it->since > o_.idle_ms) {
      close(it);
    } else if (!it->busy && !it->idle && now - it->since > o_.timeout_ms) {
      refuse(*it, error_response(408, "the request did not arrive in time"));
    }
    it = next;
  }
}

}  // namespace

Status Server::listen(const ServerOptions& o) {
  o_ = o;
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(uint16_t(o.port));
  if (::inet_pton(AF_INET, o.bind.c_str(), &addr.sin_addr) != 1) {
    return Status::InvalidArgument("--bind '" + o.bind + "' is not an IPv4 address");
  }
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
  int wake[2];
  if (::pipe2(wake, O_CLOEXEC | O_NONBLOCK) != 0) return;
  Queues q;
  std::vector<std::thread> pool;
  for (int i = 0; i < o_.threads; ++i) {
    pool.emplace_back([&] {
      if (on_start) on_start();
      while (Connection* c = q.pop_job()) {
        bool keep = true;
        do {
          const Request& r = c->request;
          keep = r.keep_alive && c->served + 1 < o_.max_requests && !stopping_;
          keep = send_response(c->fd, handler(r), keep, o_.timeout_ms);
          ++c->served;
        } while (keep && next_request_at_once(*c, o_.max_body));
        q.push_done(c, keep, wake[1]);
      }
    });
  }
  {
    Poller poller(o_, listen_fd_, q, open_, held_);
    poller.run(stopping_, wake[0]);
    q.close();
    for (auto& t : pool) t.join();  // before the poller closes what they hold
  }
  ::close(wake[0]);
  ::close(wake[1]);
}

}  // namespace weaver::serve
