// The keys seen last, by hash, in a small direct-mapped table: a stream
// that repeats itself nearby (the neighbours neighbouring octants ask for)
// drops most repeats here before they reach a sort.  It may let a repeat
// through (its slot was taken since), never drops a first sight.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

namespace weaver {

template <int kBits>
class RecentKeys {
 public:
  RecentKeys() { clear(); }
  void clear() { slots_.fill(kEmpty); }
  // Whether key is in its slot already; else it is put there.
  bool seen(uint64_t key) {
    uint64_t& slot = slots_[(key * 0x9E3779B97F4A7C15ULL) >> (64 - kBits)];
    const bool hit = slot == key;  // no branch: callers keep or drop by it
    slot = key;
    return hit;
  }

 private:
  static constexpr uint64_t kEmpty = ~uint64_t{0};  // no octant key
  std::array<uint64_t, size_t{1} << kBits> slots_;
};

}  // namespace weaver
