// A connection as the server's threads share it: the polling thread owns
// it while it waits for or receives a request (http_server.cc), a worker
// from a whole request until its answer is sent (answer_sender.cc), and the
// polling thread again for what a slow reader has still to take.  Internal
// to serve/.
#pragma once

#include <chrono>
#include <cstdint>
#include <initializer_list>
#include <string>
#include <string_view>

#include "serve/http.h"
#include "serve/outbox.h"

namespace weaver::serve {

inline int64_t now_ms() {
  using namespace std::chrono;
  return duration_cast<milliseconds>(steady_clock::now().time_since_epoch()).count();
}

struct Connection {
  int fd = -1;
  std::string in;             // received, not yet taken as a request
  int64_t since = 0;          // when it went idle, when its request began, or when it was queued
  bool idle = true;           // between requests, with no byte of the next
  bool busy = false;          // a worker has it
  bool draining = false;      // refused: its answer sent, the rest of its bytes read and dropped
  bool sending = false;       // the poller sends the rest of an answer (out) for a slow reader
  bool keep_after = false;    // ... after which the connection takes another request
  int served = 0;             // requests answered
  uint64_t reserved = 0;      // body bytes counted against max_buffered
  Request request;            // the request a worker answers
  std::string peer;           // the client's address, for the log
  uint64_t answer_bytes = 0;  // of the answer being sent, head included
  Outbox out;                 // what is still to send of an answer
  RateClock clock;            // how fast the client reads it
};

// What becomes of a connection after an answer: it takes another request,
// it closes once the answer is sent, or it closes now (the client is gone,
// too slow, or the answer was cut short).
enum class After { kKeep, kClose, kDrop };

// Answers c's request with r (running its stream, if it has one, unless
// the request is a HEAD): as fast as the client takes it; what a slow
// client has still to take stays in c.out, spilled within room.
After send_response(Connection& c, const Response& r, bool keep_alive, SpillRoom* room);

// Sends all of parts on a non-blocking socket within timeout_ms in all;
// false if the client is gone or too slow.  For short answers only.
bool send_parts(int fd, std::initializer_list<std::string_view> parts, int timeout_ms);

// A short answer sent at once, before the connection closes.
void send_refusal(int fd, const Response& r);

}  // namespace weaver::serve
