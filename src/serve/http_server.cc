// The Server of serve/http.h: one polling thread that owns the connections
// while they wait for or receive a request, and a pool of workers that own
// a connection from a whole request until its answer is sent
// (answer_sender.cc sends it).
#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <strings.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <deque>
#include <list>
#include <mutex>
#include <thread>
#include <vector>

#include "serve/connection.h"
#include "serve/http.h"
#include "util/printable.h"

namespace weaver::serve {
namespace {

// What a connection's bytes hold: a whole request (moved from c.in to
// c.request), not yet one (*length: the body it announces, when its head
// is in), or a mistake to answer (*refusal) before closing.
enum class Take { kRequest, kMore, kRefuse };
Take take_request(Connection& c, uint64_t max_body, uint64_t* length, Response* refusal,
                  bool* expects_continue = nullptr) {
  *length = 0;
  // Empty lines before a request are ignored (RFC 9112 2.2).
  size_t blank = 0;
  while (c.in.compare(blank, 2, "\r\n") == 0) blank += 2;
  if (blank > 0) c.in.erase(0, blank);
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
      const std::string* e = r.header("expect");
      *expects_continue = e != nullptr && ::strcasecmp(e->c_str(), "100-continue") == 0;
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
  // A worker is done with c: what becomes of it.
  void push_done(Connection* c, After keep, int wake_fd) {
    {
      std::lock_guard<std::mutex> l(m_);
      done_.push_back({c, keep});
    }
    const char b = 1;
    (void)!::write(wake_fd, &b, 1);
  }
  std::vector<std::pair<Connection*, After>> take_done() {
    std::lock_guard<std::mutex> l(m_);
    std::vector<std::pair<Connection*, After>> out(done_.begin(), done_.end());
    done_.clear();
    return out;
  }

 private:
  std::mutex m_;
  std::condition_variable ready_;
  std::deque<Connection*> jobs_;
  std::deque<std::pair<Connection*, After>> done_;
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
    send_refusal(c.fd, r);
    ::shutdown(c.fd, SHUT_WR);
    buffered_ -= c.reserved;
    c.reserved = 0;
    c.in = std::string();
    c.draining = true;
    c.since = now_ms();
    return true;
  }
  void expire(int64_t now);
  // Sends more of a slow reader's answer.
  void send_more(std::list<Connection>::iterator it);
  // An answer is sent: c takes its next request (keep) or closes.
  void answered(std::list<Connection>::iterator it, bool keep);
  void close(std::list<Connection>::iterator it) {
    it->out.release();
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
  int64_t accept_after_ = 0;         // out of descriptors: no accept before this
};

// How long the listening socket rests when descriptors run out.
constexpr int64_t kAcceptPauseMs = 100;

void Poller::run(const std::atomic<bool>& stopping, int wake_fd) {
  std::vector<pollfd> fds;
  std::vector<std::list<Connection>::iterator> polled;
  while (!stopping) {
    for (const auto& [c, after] : q_.take_done()) {
      const auto it = std::find_if(conns_.begin(), conns_.end(),
                                   [c = c](const Connection& x) { return &x == c; });
      buffered_ -= it->reserved;
      it->reserved = 0, it->busy = false;
      if (after == After::kDrop) {
        close(it);
      } else if (!it->out.empty()) {
        it->sending = true, it->keep_after = after == After::kKeep;
      } else {
        answered(it, after == After::kKeep);
      }
    }
    const int64_t now = now_ms();
    fds.assign({{wake_fd, POLLIN, 0}, {now >= accept_after_ ? listen_fd_ : -1, POLLIN, 0}});
    polled.clear();
    for (auto it = conns_.begin(); it != conns_.end(); ++it) {
      if (!it->busy) {
        fds.push_back({it->fd, short(it->sending ? POLLOUT : POLLIN), 0});
        polled.push_back(it);
      }
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
      if (c.sending) {
        send_more(polled[i]);
      } else if (!receive(c) || (!c.in.empty() && !dispatch(c))) {
        close(polled[i]);
      }
    }
    expire(now_ms());
  }
}

void Poller::send_more(std::list<Connection>::iterator it) {
  if (!it->out.send_some(it->fd, &it->clock.bytes)) return close(it);
  if (!it->out.empty()) return;
  it->out.release();
  it->sending = false;
  answered(it, it->keep_after);
}

void Poller::answered(std::list<Connection>::iterator it, bool keep) {
  it->idle = it->in.empty(), it->since = now_ms();
  if (!keep || (!it->in.empty() && !dispatch(*it))) close(it);
}

void Poller::accept_all() {
  for (;;) {
    const int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC | SOCK_NONBLOCK);
    if (fd < 0 && (errno == EMFILE || errno == ENFILE || errno == ENOMEM || errno == ENOBUFS)) {
      // Out of descriptors: the listening socket stays readable, so it is
      // left unpolled a while rather than spun on.
      accept_after_ = now_ms() + kAcceptPauseMs;
      return;
    }
    if (fd < 0) return;  // none left (EAGAIN), or the client left
    const int one = 1;   // answers go out whole, at once
    ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    if (int(conns_.size()) >= o_.max_connections) {
      send_refusal(fd, error_response(503, "too many connections (" +
                                               std::to_string(o_.max_connections) + "): retry"));
      ::close(fd);
      continue;
    }
    Connection c;
    c.fd = fd;
    c.since = now_ms();
    sockaddr_in peer{};
    socklen_t len = sizeof peer;
    char ip[INET_ADDRSTRLEN] = "?";
    if (::getpeername(fd, reinterpret_cast<sockaddr*>(&peer), &len) == 0) {
      ::inet_ntop(AF_INET, &peer.sin_addr, ip, sizeof ip);
    }
    c.peer = std::string(ip) + ":" + std::to_string(ntohs(peer.sin_port));
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
  c.since = now_ms();  // queued: a worker that finds it waited too long answers 503
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
    } else if (it->sending) {
      if (!it->clock.keeps_up(now)) close(it);  // reads slower than kMinRate
    } else if (!it->busy && it->idle && now - it->since > o_.idle_ms) {
      close(it);
    } else if (!it->busy && !it->idle && now - it->since > o_.timeout_ms) {
      refuse(*it, error_response(408, "the request did not arrive in time"));
    }
    it = next;
  }
}

// The handler's answer to r; an exception (an allocation that failed, say)
// is a 500, logged, never the end of the process.
Response answer(const Server::Handler& handler, const Request& r) {
  try {
    return handler(r);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "weaver serve: %s %s: %s\n", r.method.c_str(), printable(r.path).c_str(),
                 e.what());
    return error_response(500, "the request failed on the server");
  }
}

// One line on stderr a request: when, who, what, and how it went.
void log_request(const Connection& c, int status, int64_t ms) {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char when[32];
  std::strftime(when, sizeof when, "%Y-%m-%dT%H:%M:%SZ", &tm);
  std::fprintf(stderr, "%s %s %s %s %d %llu %lldms\n", when, c.peer.c_str(),
               printable(c.request.method, 16).c_str(), printable(c.request.path, 200).c_str(),
               status, (unsigned long long)c.answer_bytes, (long long)ms);
}

}  // namespace

Status Server::listen(const ServerOptions& o) {
  o_ = o;
  spill_.dir = o.scratch_dir;
  spill_.limit = o.max_spill;
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
        After after = After::kKeep;
        do {
          const Request& r = c->request;
          const int64_t start = now_ms();
          const bool keep = r.keep_alive && c->served + 1 < o_.max_requests && !stopping_;
          const Response res = start - c->since > o_.timeout_ms
                                   ? error_response(503, "the server is busy: retry")
                                   : answer(handler, r);
          c->answer_bytes = 0;
          after = send_response(*c, res, keep, &spill_);
          ++c->served;
          if (o_.log) log_request(*c, res.status, now_ms() - start);
          c->since = now_ms();
        } while (after == After::kKeep && c->out.empty() && next_request_at_once(*c, o_.max_body));
        q.push_done(c, after, wake[1]);
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
