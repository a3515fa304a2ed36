// Keeps the memory the program frees for its own next allocations, rather
// than giving it back to the system at once.
//
// glibc serves a large block (from 128 KiB, rising to the largest freed
// one) by a mapping of its own, unmapped when freed, and trims the top of
// a heap once it has twice that free.  A construct fills, writes and frees
// a subtree's vectors of leaves (megabytes) for each subtree, and
// each new one was faulted in again page by page: the 2 Hz basin's
// construct at --memory 1G took 891K page faults and 5.6-7.3 s of system
// time (on a virtual machine a fault costs microseconds).
// With blocks of up to 32 MiB taken from the heap and its top trimmed only
// past 64 MiB free (the most glibc's own rule ever sets), it took 67K and
// 0.953x the wall (docs/performance.md, stop 85).  The
// memory kept is what the program held a moment before: the peak stayed
// within a few MB of before at 64M, 256M and 1G.
#pragma once

#include <cstdlib>  // defines __GLIBC__ where it is glibc

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace weaver {

// Call once, before any thread starts.  Does nothing but on glibc.
inline void keep_freed_memory() {
#if defined(__GLIBC__) && defined(M_MMAP_THRESHOLD) && defined(M_TRIM_THRESHOLD)
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_TRIM_THRESHOLD, 64 << 20);
#endif
}

}  // namespace weaver
