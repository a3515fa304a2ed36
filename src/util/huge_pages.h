// Large arrays that are filled once and then walked (a batch of a million
// points, its sort buffers, its answers) take a page fault per 4 KiB when
// first touched; on a virtual machine a fault costs microseconds, and a
// batch's faults cost more than its answers.  Asking the kernel for
// transparent huge pages on such an array cuts them 512-fold.
#pragma once

#include <sys/mman.h>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace weaver {

// Reserves room for n items in v and advises huge pages for the whole
// 2 MiB-aligned part of it.  A hint: nothing changes where the kernel
// cannot (or is told not to) use huge pages.
template <class T>
void reserve_huge(std::vector<T>& v, size_t n) {
  if (v.capacity() >= n) return;
  v.reserve(n);
#ifdef MADV_HUGEPAGE
  constexpr uintptr_t kHuge = uintptr_t{2} << 20;
  const uintptr_t begin = (reinterpret_cast<uintptr_t>(v.data()) + kHuge - 1) & ~(kHuge - 1);
  const uintptr_t end = (reinterpret_cast<uintptr_t>(v.data() + n)) & ~(kHuge - 1);
  if (end > begin) ::madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);
#endif
}

}  // namespace weaver
