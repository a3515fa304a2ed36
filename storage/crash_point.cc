#include "storage/crash_point.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <mutex>
#include <vector>

namespace weaver::crash_point {
namespace {

struct Range {
  uint64_t offset;
  size_t n;
};

struct State {
  bool enabled = false;
  uint64_t crash_at = 0;  // 0: count only
  uint64_t fail_at = 0;   // WEAVER_FAIL_AT: the step that fails
  int fail_errno = EIO;
  uint64_t steps = 0;
  std::mutex mu;
  std::map<int, std::vector<Range>> unsynced;  // by fd

  State() {
    if (const char* f = std::getenv("WEAVER_FAIL_AT"); f != nullptr && *f != '\0') {
      enabled = true;
      fail_at = std::strtoull(f, nullptr, 10);
      const char* e = std::getenv("WEAVER_FAIL_ERRNO");
      if (e != nullptr && std::strcmp(e, "ENOSPC") == 0) fail_errno = ENOSPC;
    }
    const char* v = std::getenv("WEAVER_CRASH_AT");
    if (v == nullptr || *v == '\0') return;
    enabled = true;
    crash_at = std::strtoull(v, nullptr, 10);
    if (crash_at == 0)
      std::atexit([] {
        std::fprintf(stderr, "crash steps: %llu\n", (unsigned long long)instance().steps);
        // Also to a file, for a process whose stderr goes nowhere (a rank of
        // weaver-mpi other than 0).
        const char* to = std::getenv("WEAVER_CRASH_STEPS_FILE");
        std::FILE* f = to != nullptr ? std::fopen(to, "w") : nullptr;
        if (f != nullptr) {
          std::fprintf(f, "%llu\n", (unsigned long long)instance().steps);
          std::fclose(f);
        }
      });
  }
  static State& instance();

  // The power cut: unsynced bytes read back as zeros.
  [[noreturn]] void die() {
    std::vector<char> zeros(1 << 16, 0);
    for (const auto& [fd, ranges] : unsynced) {
      for (const Range& r : ranges) {
        for (uint64_t done = 0; done < r.n;) {
          const size_t chunk = std::min<uint64_t>(zeros.size(), r.n - done);
          if (::pwrite(fd, zeros.data(), chunk, static_cast<off_t>(r.offset + done)) <= 0) break;
          done += chunk;
        }
      }
    }
    ::_exit(137);
  }
};

State& State::instance() {
  static State s;
  return s;
}

}  // namespace

int step() {
  State& s = State::instance();
  if (!s.enabled) return 0;
  std::lock_guard<std::mutex> lock(s.mu);
  if (++s.steps == s.crash_at) s.die();
  return s.steps == s.fail_at ? s.fail_errno : 0;
}

void arm(uint64_t n) {
  State& s = State::instance();
  std::lock_guard<std::mutex> lock(s.mu);
  s.enabled = true;
  s.steps = 0;
  s.crash_at = n;
}

void disarm() {
  State& s = State::instance();
  std::lock_guard<std::mutex> lock(s.mu);
  s.enabled = false;
  s.unsynced.clear();
}

uint64_t steps_taken() {
  State& s = State::instance();
  std::lock_guard<std::mutex> lock(s.mu);
  return s.steps;
}

void note_write(int fd, uint64_t offset, size_t n) {
  State& s = State::instance();
  if (!s.enabled) return;
  std::lock_guard<std::mutex> lock(s.mu);
  s.unsynced[fd].push_back({offset, n});
}

void note_sync(int fd) {
  State& s = State::instance();
  if (!s.enabled) return;
  std::lock_guard<std::mutex> lock(s.mu);
  s.unsynced.erase(fd);
}

// A file closed with bytes it never synced keeps them only as far as the
// page cache does: a power cut loses them still.  Its ranges move to a
// duplicate of the descriptor (kept open to the end: this is a test mode),
// so that die() can zero them whatever the file is called by then.
void note_close(int fd) {
  State& s = State::instance();
  if (!s.enabled) return;
  std::lock_guard<std::mutex> lock(s.mu);
  const auto it = s.unsynced.find(fd);
  if (it == s.unsynced.end()) return;
  const int kept = ::fcntl(fd, F_DUPFD_CLOEXEC, 0);
  if (kept >= 0) s.unsynced[kept] = std::move(it->second);
  s.unsynced.erase(fd);
}

}  // namespace weaver::crash_point
