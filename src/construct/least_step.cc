#include "construct/least_step.h"

#include <array>
#include <cmath>
#include <cstring>

#include "schema/octant.h"

namespace weaver {

// One division a leaf waited on the divider and on memory (5% of the 2 Hz
// construct).  Instead each level's largest vp is found, the first of
// equals: a level's least edge / vp is its edge over that vp, since a
// division by a larger number never gives more, and two floats' quotients
// of one edge never round to one double.  Levels whose steps tie (edges and
// vps a power of two apart) give it to the first leaf.  A run with a vp
// that is not positive (or NaN) is divided leaf by leaf, whose answers then
// differ in sign or order.  The leaves are read ahead (prefetched): the
// table's append reads them next, and a worker wrote them long before.
void note_least_step(const uint64_t* keys, const std::byte* payloads, size_t n, size_t bytes,
                     double tick_m, uint64_t before, double* least, uint64_t* element) {
  constexpr size_t kAhead = 128;            // leaves: 1 KiB of keys
  std::array<float, kMaxLevel + 1> most{};  // 0: none yet, as every vp counted is more
  std::array<size_t, kMaxLevel + 1> first{};
  bool odd = false;
  for (size_t i = 0; i < n; ++i) {
    __builtin_prefetch(keys + i + kAhead);
    __builtin_prefetch(payloads + (i + kAhead) * bytes);
    float vp;
    std::memcpy(&vp, payloads + i * bytes, 4);
    const int level = octant_key_level(keys[i]);
    odd |= !(vp > 0);
    if (vp > most[level]) most[level] = vp, first[level] = i;
  }
  auto take = [&](double dt, size_t i) {
    if (dt < *least) *least = dt, *element = before + i;
  };
  if (odd) {
    for (size_t i = 0; i < n; ++i) {
      float vp;
      std::memcpy(&vp, payloads + i * bytes, 4);
      take(octant_edge(octant_key_level(keys[i])) * tick_m / vp, i);
    }
    return;
  }
  double run_least = HUGE_VAL;
  size_t at = 0;
  for (int l = 0; l <= kMaxLevel; ++l) {
    if (most[l] == 0) continue;
    const double dt = octant_edge(l) * tick_m / most[l];
    if (dt < run_least || (dt == run_least && first[l] < at)) run_least = dt, at = first[l];
  }
  take(run_least, at);
}

}  // namespace weaver
