#include "util/progress.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "util/printable.h"

namespace weaver {
namespace {

constexpr auto kTerminalPeriod = std::chrono::milliseconds(250);

// Between plain lines: 10 s, or WEAVER_PROGRESS_SECONDS (for logs that want
// more or fewer lines, and for tests).
std::chrono::steady_clock::duration line_period() {
  const char* env = std::getenv("WEAVER_PROGRESS_SECONDS");
  const double s = env != nullptr ? std::atof(env) : 10.0;
  return std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(std::max(0.0, s)));
}

// 12345678 as "12 345 678".
std::string grouped(uint64_t v) {
  std::string digits = std::to_string(v), out;
  for (size_t i = 0; i < digits.size(); ++i) {
    if (i > 0 && (digits.size() - i) % 3 == 0) out += ' ';
    out += digits[i];
  }
  return out;
}

// 95 s as "1:35", 3700 s as "1:01:40".
std::string clock_text(double seconds) {
  const long s = std::lround(std::max(0.0, seconds));
  char buf[32];
  if (s >= 3600) {
    std::snprintf(buf, sizeof buf, "%ld:%02ld:%02ld", s / 3600, s / 60 % 60, s % 60);
  } else {
    std::snprintf(buf, sizeof buf, "%ld:%02ld", s / 60, s % 60);
  }
  return buf;
}

}  // namespace

ProgressLine::Style ProgressLine::style_for_stderr(bool quiet) {
  if (quiet) return Style::kNone;
  return ::isatty(STDERR_FILENO) ? Style::kTerminal : Style::kLines;
}

ProgressLine::ProgressLine(Style style, std::string stage, std::string unit)
    : style_(style), stage_(std::move(stage)), unit_(std::move(unit)), start_(Clock::now()) {
  period_ = style_ == Style::kTerminal
                ? std::chrono::duration_cast<Clock::duration>(kTerminalPeriod)
                : line_period();
  // The first line waits too: short runs print nothing.
  next_ = start_ + (style_ == Style::kTerminal ? 2 * period_ : period_);
}

std::string ProgressLine::describe(uint64_t items, double fraction, double seconds,
                                   const std::string& unit) {
  std::string text;
  if (fraction >= 0) {
    char pct[16];
    std::snprintf(pct, sizeof pct, "%.1f%%", 100 * std::min(fraction, 1.0));
    text = std::string(pct) + "  ";
  }
  text += grouped(items) + " " + unit;
  if (seconds > 0) text += "  " + si_text(items / seconds) + "/s";
  if (fraction > 0.005 && fraction < 1) {
    text += "  " + clock_text(seconds * (1 - fraction) / fraction) + " left";
  }
  return text;
}

void ProgressLine::update(uint64_t items, double fraction) {
  if (style_ == Style::kNone) return;
  const Clock::time_point now = Clock::now();
  if (now < next_) return;
  next_ = now + period_;
  const double seconds = std::chrono::duration<double>(now - start_).count();
  const std::string text = describe(items, fraction, seconds, unit_);
  if (style_ == Style::kTerminal) {
    // Pad over the previous, possibly longer, text.
    std::fprintf(stderr, "\r%-10s %-70s", stage_.c_str(), text.c_str());
  } else {
    std::fprintf(stderr, "%s: %s\n", stage_.c_str(), text.c_str());
  }
  std::fflush(stderr);
  shown_ = true;
}

void ProgressLine::finish() {
  if (style_ == Style::kTerminal && shown_) std::fprintf(stderr, "\r%81s\r", "");
  shown_ = false;
}

}  // namespace weaver
