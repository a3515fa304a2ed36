// A vector whose resize() leaves new trivial items uninitialised, for
// buffers that are grown and then written whole: std::vector value-
// initialises them, a memset of every byte before the real writes (3% of
// the 2 Hz construct's samples, in its leaves' keys and records).
#pragma once

#include <memory>
#include <new>
#include <utility>
#include <vector>

namespace weaver {

template <class T>
struct DefaultInitAllocator : std::allocator<T> {
  template <class U>
  struct rebind {
    using other = DefaultInitAllocator<U>;
  };
  DefaultInitAllocator() = default;
  template <class U>
  DefaultInitAllocator(const DefaultInitAllocator<U>&) noexcept {}

  // Default-initialises: nothing at all for a trivial U.
  template <class U>
  void construct(U* p) noexcept(noexcept(::new (static_cast<void*>(p)) U)) {
    ::new (static_cast<void*>(p)) U;
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};

template <class T>
using UninitVector = std::vector<T, DefaultInitAllocator<T>>;

}  // namespace weaver
