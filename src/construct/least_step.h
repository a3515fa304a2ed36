// The least edge / vp of construct's leaves: what an explicit solver's time
// step is a Courant number times, found as the leaves are appended.
#pragma once

#include <cstddef>
#include <cstdint>

namespace weaver {

// The least edge (ticks times tick_m) / vp over leaves [0, n) (keys, and
// payloads of `bytes` each whose first f32 is vp), into *least and its
// leaf's element number (`before` plus its index) into *element where it is
// less than *least: the first of equals, as a division a leaf in order
// would find it.
void note_least_step(const uint64_t* keys, const std::byte* payloads, size_t n, size_t bytes,
                     double tick_m, uint64_t before, double* least, uint64_t* element);

}  // namespace weaver
