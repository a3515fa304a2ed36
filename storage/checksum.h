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

// Whether readers compare stored checksums: always (storage/checksum_policy.cc),
// except in the libFuzzer targets, which link fuzz/checksums_off.cc's
// definition instead (a mismatch would stop every mutated input at the
// checksum, and the decoders behind it would never be exercised).  A link-time
// choice, so that the tests and the fuzz targets share one instrumented build
// of the libraries and the product can never turn the checks off.
bool checksums_enforced();

}  // namespace weaver
