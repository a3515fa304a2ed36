// Binary search over the sorted u64 key column of a page.
#pragma once

#include <cstdint>

#include "storage/page_format.h"

namespace weaver::page {

// Issues prefetches for the n-key column (and so the page header before it):
// a binary search over a cold page then pays about one memory latency
// instead of one per probe.
inline void prefetch_keys(const std::byte* keys, uint32_t n) {
  for (size_t off = 0; off < 8 * size_t{n}; off += 64) __builtin_prefetch(keys + off);
}

// The first i in [0, n) with key[i] >= k, or n.  Branch-free: the loop runs
// log2(n) times whatever the data, which beats a branchy search on random keys.
inline uint32_t lower_bound(const std::byte* keys, uint32_t n, uint64_t k) {
  if (n == 0) return 0;
  uint32_t lo = 0, len = n;
  while (len > 1) {
    const uint32_t half = len / 2;
    lo = load64(keys + 8 * size_t{lo + half - 1}) < k ? lo + half : lo;
    len -= half;
  }
  return lo + (load64(keys + 8 * size_t{lo}) < k ? 1 : 0);
}

// The first i in [0, n) with key[i] > k, or n.
inline uint32_t upper_bound(const std::byte* keys, uint32_t n, uint64_t k) {
  if (n == 0) return 0;
  uint32_t lo = 0, len = n;
  while (len > 1) {
    const uint32_t half = len / 2;
    lo = load64(keys + 8 * size_t{lo + half - 1}) <= k ? lo + half : lo;
    len -= half;
  }
  return lo + (load64(keys + 8 * size_t{lo}) <= k ? 1 : 0);
}

// The child of an internal page that routes key k: the last i >= 1 with
// key[i] <= k, or 0.  key[0] is skipped: it routes nothing and may be stale
// (larger than key[1]) after inserts below the page's old minimum.
// REQUIRES: n >= 1.
inline uint32_t child_index(const std::byte* keys, uint32_t n, uint64_t k) {
  return upper_bound(keys + 8, n - 1, k);
}

}  // namespace weaver::page
