// A crash simulator for tests, built into the engine but idle unless the
// environment variable WEAVER_CRASH_AT is set.
//
// Every durable step a writer takes (a write or sync of a file, a rename)
// counts one.  With WEAVER_CRASH_AT=N the process dies at its N-th step, as
// a power cut would leave it: before dying it zeroes every byte written to a
// still-open file since that file's last sync, which is what the disk may
// hold for writes that never reached it.  With WEAVER_CRASH_AT=0 nothing
// dies and the step count is printed to stderr at exit ("crash steps: N"),
// so a harness can spread its kill points over a writer's whole run (and
// to the file WEAVER_CRASH_STEPS_FILE names, when set).
//
// Faults instead of deaths: with WEAVER_FAIL_AT=N the N-th step fails with
// the error WEAVER_FAIL_ERRNO names (EIO, the default, or ENOSPC) instead of
// being taken, as a bad or full disk would fail it, and the process goes on.
#pragma once

#include <cstddef>
#include <cstdint>

namespace weaver::crash_point {

// Counts a step; dies if it is the chosen one, or returns the errno it
// must fail with (0: go ahead).  Cheap when idle.
[[nodiscard]] int step();
// Tests that fork a writer arm the simulator in the child instead of through
// the environment: die at step n from now (0: only count).  steps_taken()
// is the count so far.
void arm(uint64_t n);
void disarm();
uint64_t steps_taken();
// Bookkeeping for the zeroing: a write of n bytes at offset to fd, a sync of
// fd, and fd closing.
void note_write(int fd, uint64_t offset, size_t n);
void note_sync(int fd);
void note_close(int fd);

}  // namespace weaver::crash_point
