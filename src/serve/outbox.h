// What a connection has still to send of an answer, and the rule a slow
// reader is held to.  A worker writes an answer into its connection's
// Outbox and sends what the socket takes at once; when the client reads
// too slowly to keep up, the rest waits in the Outbox (in memory up to
// kHeldBytes, past that in a spill file in the server's scratch
// directory) and the polling thread sends it as the socket drains, so the
// worker goes on to other requests: a slow reader holds a connection and
// some disk, never a thread.  An answer that drains slower than kMinRate,
// averaged over kRateWindowMs, is dropped (RateClock).
#pragma once

#include <sys/types.h>

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

namespace weaver::serve {

// The bytes of an answer's body in a file: an export written first, or a
// spill file (which grows as it is written).  Closes its descriptor.
struct FileBody {
  explicit FileBody(int fd_ = -1, uint64_t size_ = 0) : fd(fd_), size(size_) {}
  ~FileBody();
  FileBody(const FileBody&) = delete;
  FileBody& operator=(const FileBody&) = delete;
  int fd;
  uint64_t size;
};

// Where spill files go, and how many bytes they may hold at once in all:
// past that a worker waits for its client rather than spill more.
struct SpillRoom {
  std::string dir;
  uint64_t limit = 1ull << 30;
  std::atomic<uint64_t> used{0};
};

inline constexpr size_t kHeldBytes = 256 << 10;  // an Outbox's bytes in memory
inline constexpr uint64_t kMinRate = 64 << 10;   // bytes a second, at least
inline constexpr int64_t kRateWindowMs = 10000;  // averaged over this long

class Outbox {
 public:
  Outbox() = default;
  Outbox(Outbox&&) = default;
  Outbox& operator=(Outbox&&) = default;
  ~Outbox() { release(); }

  bool empty() const { return bytes_.size() == at_ && (!file_ || off_ == file_->size); }
  // Queues data after what is queued: held in memory, or past kHeldBytes
  // appended to a spill file.  False when it can be neither (no room to
  // spill, or the file cannot be written): then nothing was queued.
  bool add(std::string_view data, SpillRoom* room);
  // Queues the file's bytes after what is queued (nothing may follow them).
  void add_file(std::shared_ptr<FileBody> file) { file_ = std::move(file), off_ = 0; }
  // Sends what the socket takes now; adds the bytes sent to *sent.  False
  // when the client is gone.
  bool send_some(int fd, uint64_t* sent);
  // Forgets what is queued, and gives back its spill room.
  void release();

 private:
  std::string bytes_;
  size_t at_ = 0;  // bytes_ before this are sent
  std::shared_ptr<FileBody> file_;
  uint64_t off_ = 0;
  SpillRoom* spill_ = nullptr;  // set: file_ is a spill file counted in it
};

// The minimum rate of an answer: each window of kRateWindowMs must see at
// least kMinRate x the window sent, unless the answer is done.
struct RateClock {
  int64_t since = 0;
  uint64_t bytes = 0;
  void start(int64_t now) { since = now, bytes = 0; }
  // False when the window that ended by `now` fell short.
  bool keeps_up(int64_t now) {
    if (now - since < kRateWindowMs) return true;
    const bool ok = bytes >= kMinRate * uint64_t(now - since) / 1000;
    start(now);
    return ok;
  }
};

}  // namespace weaver::serve
