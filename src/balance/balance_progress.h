// Balance's progress: the fraction done of its three parts.  The first pass
// reads the leaves (counted 13%), the level passes expand the closure from
// fine to coarse (46%, shared among levels by the leaves one level finer,
// whose parents each pass expands), the final pass writes the refinement
// (41%, by leaves read).  The weights are the parts' shares of the time of
// the 1 Hz basin on 2 threads (1.0-1.3, 3.9-4.0 and 3.6 s of 8.5-8.9 s,
// timed with the domain map; the 0.5 Hz basin gives 17/46/37); the count
// shown is the leaves read by the current pass.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>

#include "db/octant_table.h"
#include "schema/octant.h"
#include "util/progress.h"

namespace weaver {

class BalanceProgress {
 public:
  static constexpr double kScan = 0.13, kLevels = 0.46;
  static constexpr uint64_t kEvery = 1 << 16;  // leaves between reports

  BalanceProgress(ProgressFn fn, uint64_t leaves, const LevelCounts& levels)
      : fn_(std::move(fn)), leaves_(leaves > 0 ? leaves : 1) {
    double total = 0;
    for (int l = 0; l < kMaxLevel; ++l) total += double(levels[l + 1]) + 1;
    double before = 0;
    for (int l = kMaxLevel - 1; l >= 0; --l) {  // passes run fine to coarse
      before += double(levels[l + 1]) + 1;
      level_end_[l] = kScan + kLevels * before / total;
    }
  }

  void scanned(uint64_t n) {
    if (fn_ && n % kEvery == 0) fn_(n, kScan * double(n) / leaves_);
  }
  // Part way through a level's pass: f in [0, 1] of it.
  void within_level(int level, double f) {
    if (!fn_) return;
    const double start = level + 1 < kMaxLevel ? level_end_[level + 1] : kScan;
    fn_(leaves_, start + std::min(f, 1.0) * (level_end_[level] - start));
  }
  void level_done(int level) {
    if (fn_) fn_(leaves_, level_end_[level]);
  }
  void refined(uint64_t n) {
    if (fn_ && n % kEvery == 0) fn_(n, kScan + kLevels + (1 - kScan - kLevels) * n / leaves_);
  }

 private:
  ProgressFn fn_;
  double leaves_;
  std::array<double, kMaxLevel> level_end_{};
};

}  // namespace weaver
