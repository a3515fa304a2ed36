// Sending an answer (serve/connection.h): straight from its bytes to the
// socket while the client keeps up, into the connection's Outbox once it is
// slow (serve/outbox.h); streamed answers in chunks past kStreamHold, or
// close-delimited to HTTP/1.0; HEAD without a body.
#include <poll.h>
#include <sys/socket.h>
#include <sys/uio.h>

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cstdio>
#include <exception>
#include <vector>

#include "serve/connection.h"
#include "util/printable.h"

namespace weaver::serve {

// Sends all of parts, in order, on a non-blocking socket (one sendmsg for
// all that fits: a head and a short body in two sends would wait on the
// client's delayed ACK), waiting for room at most timeout_ms in all; false
// if the client is gone or too slow.  For short answers only (refusals,
// 100 Continue): an answer goes through the connection's Outbox.
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

namespace {

// How long a worker waits for a client to take more of an answer before
// it calls the client slow and leaves the rest to the polling thread: a
// client on a busy machine stalls 50 ms now and then (and its answer would
// go to disk for nothing), and a slow one costs a worker no more than this.
constexpr int kPatienceMs = 200;

// A worker's side of sending an answer on c: bytes go into c.out and out
// to the socket as fast as the client takes them; once the client is slow
// the rest stays queued (spilled past kHeldBytes), for the poller.  When
// no spill room is left the worker waits, held to the minimum rate.
class Sender {
 public:
  Sender(Connection& c, SpillRoom* room) : c_(c), room_(room) { c_.clock.start(now_ms()); }

  // Sends data after what is queued: straight from data to the socket
  // while the client keeps up (waiting for it kPatienceMs at most at a
  // time), into the outbox once it is slow.
  bool put(std::string_view data) {
    if (failed_) return false;
    c_.answer_bytes += data.size();
    while (!data.empty() && !slow_ && c_.out.empty()) {
      const ssize_t n = ::send(c_.fd, data.data(), data.size(), MSG_NOSIGNAL);
      if (n > 0) {
        data.remove_prefix(size_t(n)), c_.clock.bytes += uint64_t(n);
      } else if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
        if (!c_.clock.keeps_up(now_ms())) return failed_ = true, false;
        pollfd p{c_.fd, POLLOUT, 0};
        if (::poll(&p, 1, kPatienceMs) == 0) slow_ = true;  // the rest waits for the poller
      } else if (!(n < 0 && errno == EINTR)) {
        return failed_ = true, false;  // the client is gone
      }
    }
    if (data.empty()) return true;
    if (!c_.out.add(data, room_)) {  // no room to spill: wait for the client
      while (!failed_ && !c_.out.empty()) failed_ = !wait_once(kRateWindowMs);
      failed_ = failed_ || !c_.out.add(data, room_);
      return !failed_;
    }
    return drain();
  }
  void put_file(std::shared_ptr<FileBody> f) {
    c_.answer_bytes += f->size;
    c_.out.add_file(std::move(f));
    drain();
  }
  // Sends what the client takes now, waiting a little while it keeps up.
  bool drain() {
    while (!failed_ && !c_.out.empty()) {
      if (!send_now()) return false;
      if (c_.out.empty() || slow_) break;
      pollfd p{c_.fd, POLLOUT, 0};
      if (::poll(&p, 1, kPatienceMs) == 0) slow_ = true;  // the rest waits for the poller
    }
    return !failed_;
  }
  bool failed() const { return failed_; }

 private:
  bool send_now() {
    failed_ = failed_ || !c_.out.send_some(c_.fd, &c_.clock.bytes) || !c_.clock.keeps_up(now_ms());
    if (c_.out.empty()) slow_ = false;  // caught up: worth waiting for again
    return !failed_;
  }
  // Waits for room on the socket at most ms, then sends.
  bool wait_once(int ms) {
    pollfd p{c_.fd, POLLOUT, 0};
    if (::poll(&p, 1, std::min(ms, 200)) < 0 && errno != EINTR) return false;
    return send_now();
  }

  Connection& c_;
  SpillRoom* room_;
  bool slow_ = false, failed_ = false;
};

// A streamed answer's sink: it holds the first kStreamHold bytes; an
// answer that ends within them goes out whole with its Content-Length.
// Past them the head goes out, then each write as a chunk of its own (the
// stream's stdio buffer makes them 256 KiB), or, to an HTTP/1.0 client,
// as it is, the connection's close ending it.
class SocketSink : public BodySink {
 public:
  SocketSink(Sender& out, const Response& head, bool keep_alive, bool http10)
      : out_(out), head_(head), keep_(keep_alive), http10_(http10) {}

  bool write(const char* data, size_t n) override {
    if (out_.failed()) return false;
    if (!started_ && held_.size() + n <= kStreamHold) return held_.append(data, n), true;
    if (!started_) {
      started_ = true;
      const Framing f = http10_ ? Framing::kClose : Framing::kChunked;
      if (!out_.put(response_head(head_, keep_ && !http10_, f)) || !chunk(held_)) return false;
      held_ = std::string();
    }
    return chunk(std::string_view(data, n));
  }

  // Ends the answer as the stream said (end).
  After finish(Response end) {
    const After done = keep_ ? After::kKeep : After::kClose;
    if (!started_) {
      Response whole = end.status != 200 ? std::move(end) : head_;
      if (whole.status == 200) whole.stream = nullptr, whole.body = std::move(held_);
      return out_.put(response_head(whole, keep_) + whole.body) ? done : After::kDrop;
    }
    if (out_.failed() || end.status != 200) return After::kDrop;  // cut short: the client sees it
    if (http10_) return After::kClose;                            // the close ends the body
    return out_.put("0\r\n\r\n") ? done : After::kDrop;
  }

 private:
  bool chunk(std::string_view data) {
    if (data.empty()) return true;
    if (http10_) return out_.put(data);
    char size[24];
    const int len = std::snprintf(size, sizeof size, "%zx\r\n", data.size());
    return out_.put(std::string_view(size, size_t(len))) && out_.put(data) && out_.put("\r\n");
  }

  Sender& out_;
  const Response& head_;
  bool keep_, http10_;
  bool started_ = false;
  std::string held_;
};

}  // namespace

// Answers c's request with r (running its stream, if it has one, unless
// the request is a HEAD): what is left to send stays in c.out.
After send_response(Connection& c, const Response& r, bool keep_alive, SpillRoom* room) {
  Sender out(c, room);
  const Request& q = c.request;
  const After done = keep_alive ? After::kKeep : After::kClose;
  const auto ended = [&](bool sent, After after) {
    return sent && !out.failed() ? after : After::kDrop;
  };
  if (q.method == "HEAD" && r.stream) {
    const Framing f = q.http10 ? Framing::kClose : Framing::kChunked;
    return ended(out.put(response_head(r, keep_alive && !q.http10, f)),
                 q.http10 ? After::kClose : done);
  }
  if (r.file) {
    const bool sent = out.put(response_head(r, keep_alive));
    if (q.method != "HEAD") out.put_file(r.file);
    return ended(sent, done);
  }
  if (!r.stream) {  // head and body in one send: two would wait on the client's delayed ACK
    std::string whole = response_head(r, keep_alive);
    if (q.method != "HEAD") whole += r.body;
    return ended(out.put(whole), done);
  }
  SocketSink sink(out, r, keep_alive, q.http10);
  Response end;
  try {
    end = r.stream(sink);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "weaver serve: %s %s: %s\n", q.method.c_str(), printable(q.path).c_str(),
                 e.what());
    end = error_response(500, "the answer failed");
  }
  return sink.finish(std::move(end));
}

// A short answer sent at once, before the connection closes.
void send_refusal(int fd, const Response& r) {
  send_parts(fd, {response_head(r, false), r.body}, 100);
}

}  // namespace weaver::serve
