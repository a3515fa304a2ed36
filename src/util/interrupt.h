// Ctrl-C in the interactive shell: while a scope is alive, SIGINT only sets
// a flag that long work checks (a points file, say), so an interrupted
// question ends with "interrupted" and the shell goes on, as sqlite3's does.
// Outside a scope, SIGINT does what it always did.
#pragma once

#include <signal.h>

#include <atomic>

namespace weaver {

inline std::atomic<bool>& interrupt_flag() {
  static std::atomic<bool> flag{false};
  return flag;
}

// Whether Ctrl-C was pressed since the last clear_interrupt().
inline bool interrupted() { return interrupt_flag().load(std::memory_order_relaxed); }
inline void clear_interrupt() { interrupt_flag().store(false, std::memory_order_relaxed); }

class InterruptScope {
 public:
  InterruptScope() {
    struct sigaction sa = {};
    sa.sa_handler = [](int) { interrupt_flag().store(true, std::memory_order_relaxed); };
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = SA_RESTART;
    sigaction(SIGINT, &sa, &saved_);
  }
  ~InterruptScope() { sigaction(SIGINT, &saved_, nullptr); }
  InterruptScope(const InterruptScope&) = delete;
  InterruptScope& operator=(const InterruptScope&) = delete;

 private:
  struct sigaction saved_ = {};
};

}  // namespace weaver
