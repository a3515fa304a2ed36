// Progress of a long stage, shown on stderr.
//
// Stages report through a ProgressFn in their options (items done and the
// fraction of the stage done, or -1 when they cannot tell) and know nothing
// of terminals.  The commands turn it into a ProgressLine:
//  - on a terminal, one line per stage that rewrites itself at most 4 times
//    a second: "construct  42.1%  12 345 678 leaves  3.41M/s  0:35 left";
//  - otherwise (a log file, a pipe) a plain line every 10 s (or every
//    $WEAVER_PROGRESS_SECONDS);
//  - nothing with --quiet.
// The time left is elapsed x (1 - f) / f: as honest as the stage's fraction,
// which each stage's header explains.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <string>

namespace weaver {

// items: done so far, in the stage's unit; fraction: of the stage, in
// [0, 1], or -1 if unknown.  Cheap to call often: the line rate-limits.
using ProgressFn = std::function<void(uint64_t items, double fraction)>;

class ProgressLine {
 public:
  enum class Style { kNone, kTerminal, kLines };
  // kTerminal if stderr is a terminal, else kLines; kNone when quiet.
  static Style style_for_stderr(bool quiet);

  ProgressLine(Style style, std::string stage, std::string unit);
  ~ProgressLine() { finish(); }
  ProgressLine(const ProgressLine&) = delete;
  ProgressLine& operator=(const ProgressLine&) = delete;

  void update(uint64_t items, double fraction);
  // A ProgressFn that updates this line (which must outlive it).
  ProgressFn fn() {
    return [this](uint64_t items, double fraction) { update(items, fraction); };
  }
  // Clears a terminal line; the stage prints its own summary after.
  void finish();

  // The text of one update, for tests: "42.1%  12 345 678 leaves  3.41M/s  0:35 left".
  static std::string describe(uint64_t items, double fraction, double seconds,
                              const std::string& unit);

 private:
  using Clock = std::chrono::steady_clock;
  Style style_;
  std::string stage_, unit_;
  Clock::time_point start_, next_;
  Clock::duration period_;
  bool shown_ = false;
};

}  // namespace weaver
