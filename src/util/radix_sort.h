// Least-significant-digit radix sort of 64-bit values on bits [first,
// first + bits) (higher bits must be zero; lower ones ride along), 11 bits
// a pass.  For the tens of
// thousands of nodes of one extraction bucket it is several times faster
// than std::sort: a few sequential passes instead of log2(n) rounds of
// unpredictable branches.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace weaver {

// Sorts `values` ascending by bits [first, first + bits), stably;
// `scratch` is resized and used as the other buffer.  Every digit's counts
// come from one read of the values (not a read a pass), and a digit that
// is the same in every value is not passed over.
// REQUIRES: every value < 2^(first + bits) <= 2^64.
inline void radix_sort(std::vector<uint64_t>& values, int first, int bits,
                       std::vector<uint64_t>& scratch) {
  constexpr int kDigit = 11;
  constexpr size_t kBuckets = size_t{1} << kDigit;
  constexpr int kMostPasses = (64 + kDigit - 1) / kDigit;
  const int passes = bits <= 0 ? 0 : (bits + kDigit - 1) / kDigit;
  const size_t n = values.size();
  if (passes == 0 || n < 2) return;
  scratch.resize(n);
  // Every pass's counts, a thread's own, not on its stack.
  thread_local std::vector<size_t> table;
  table.resize(size_t{kMostPasses} * kBuckets);
  std::fill(table.begin(), table.begin() + passes * kBuckets, 0);
  // The pass count known when compiled: the loop over passes unrolls (it
  // was half the counting's instructions).
  auto count_all = [&]<int kPasses>() {
    size_t* t = table.data();
    for (uint64_t v : values) {
      for (int p = 0; p < kPasses; ++p)
        ++t[p * kBuckets + ((v >> (first + p * kDigit)) & (kBuckets - 1))];
    }
  };
  switch (passes) {
    case 1: count_all.template operator()<1>(); break;
    case 2: count_all.template operator()<2>(); break;
    case 3: count_all.template operator()<3>(); break;
    case 4: count_all.template operator()<4>(); break;
    case 5: count_all.template operator()<5>(); break;
    default: count_all.template operator()<kMostPasses>(); break;
  }
  for (int p = 0; p < passes; ++p) {
    size_t* count = table.data() + p * kBuckets;
    const int shift = first + p * kDigit;
    if (count[(values[0] >> shift) & (kBuckets - 1)] == n) continue;  // one digit: in order
    size_t sum = 0;
    for (size_t d = 0; d < kBuckets; ++d) sum += std::exchange(count[d], sum);
    for (uint64_t v : values) scratch[count[(v >> shift) & (kBuckets - 1)]++] = v;
    values.swap(scratch);
  }
}

// Sorts records by a 64-bit key, stably: key(record) gives it.  Digits that
// are the same in every key are not passed over (octant keys of one level
// share their low bits, and keys of one region their high ones).  For pairs
// of a key and a position (corner lookups, point batches) and the sorter's
// runs.  Sorts items[0..n) with scratch[0..n) as the other buffer and
// returns the one that holds the result (either).
template <class T, class KeyOf>
inline T* radix_sort_buffers(T* items, T* scratch, size_t n, KeyOf key) {
  if (n < 256) {  // a pass's counts cost more than sorting a few
    std::stable_sort(items, items + n, [&](const T& a, const T& b) { return key(a) < key(b); });
    return items;
  }
  constexpr int kDigit = 11;
  constexpr size_t kBuckets = size_t{1} << kDigit;
  uint64_t any = 0, every = ~uint64_t{0};
  for (size_t i = 0; i < n; ++i) {
    any |= key(items[i]);
    every &= key(items[i]);
  }
  const uint64_t varying = any & ~every;
  for (int shift = 0; shift < 64 && (varying >> shift) != 0; shift += kDigit) {
    if (((varying >> shift) & (kBuckets - 1)) == 0) continue;
    std::array<size_t, kBuckets> count{};
    for (size_t i = 0; i < n; ++i) ++count[(key(items[i]) >> shift) & (kBuckets - 1)];
    size_t sum = 0;
    for (size_t& c : count) {
      const size_t k = c;
      c = sum;
      sum += k;
    }
    for (size_t i = 0; i < n; ++i) {
      scratch[count[(key(items[i]) >> shift) & (kBuckets - 1)]++] = items[i];
    }
    std::swap(items, scratch);
  }
  return items;
}

// The same on a vector, the result left in items.
template <class T, class KeyOf>
inline void radix_sort_by(std::vector<T>& items, std::vector<T>& scratch, KeyOf key) {
  scratch.resize(items.size());
  if (radix_sort_buffers(items.data(), scratch.data(), items.size(), key) != items.data()) {
    items.swap(scratch);
  }
}

}  // namespace weaver
