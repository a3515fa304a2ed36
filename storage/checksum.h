// A fast 32-bit checksum for pages.  It guards against torn writes, bit rot
// and misdirected I/O, not against an adversary.  Four independent 64-bit
// multiply-rotate lanes keep the CPU busy (about 8 bytes per cycle), so
// verifying every page read costs little next to the read itself.
// Do not change: checksums are stored on disk.
#pragma once

#include <cstddef>
#include <cstdint>

namespace weaver {

uint32_t checksum32(const void* data, size_t n);

// Whether readers compare stored checksums.  Always, except in the fuzzing
// build (fuzz/, clang defines FUZZING_BUILD_MODE_UNSAFE_FOR_PRODUCTION there
// by our CMake option), where a mismatch would stop every mutated input at
// the checksum and the decoders behind it would never be exercised.
constexpr bool kChecksumsEnforced =
#ifdef FUZZING_BUILD_MODE_UNSAFE_FOR_PRODUCTION
    false;
#else
    true;
#endif

}  // namespace weaver
