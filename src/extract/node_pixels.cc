#include "extract/node_pixels.h"

#include <algorithm>

#include "util/radix_sort.h"

namespace weaver {
namespace {

// What sort_records packs by: the least and greatest of a set of keys and
// the bits in which any differs from the first (the lowest bit two keys
// differ in is the lowest set bit of their difference, so its trailing
// zeros are their offsets' common ones).
struct KeySpan {
  uint64_t first = 0, lo = UINT64_MAX, hi = 0, differ = 0;
  bool any = false;
  void add(uint64_t k) {
    if (!any) first = k, any = true;
    lo = k < lo ? k : lo, hi = k > hi ? k : hi;
    differ |= k ^ first;
  }
  int zeros() const { return differ == 0 ? 0 : std::countr_zero(differ); }
  // Bits of an offset (key - lo) >> zeros(); past 56 no mask fits beside it.
  int bits() const { return any ? std::bit_width((hi - lo) >> zeros()) : 0; }
};

}  // namespace

// Sorts records by key.  A radix sort on the keys' offsets from the
// smallest, less their common trailing zero bits (corners are multiples of
// the finest leaves' edge), packed with the mask into one word; std::sort if
// they do not fit in 56 bits.
void sort_records(std::vector<SpillRecord>& records, std::vector<uint64_t>& packed,
                  std::vector<uint64_t>& scratch) {
  const size_t n = records.size();
  if (n < 2) return;
  KeySpan span;
  for (const SpillRecord& r : records) span.add(r.key);
  const uint64_t lo = span.lo;
  const int zeros = span.zeros(), bits = span.bits();
  if (bits > 56) {
    std::sort(records.begin(), records.end(),
              [](const SpillRecord& a, const SpillRecord& b) { return a.key < b.key; });
    return;
  }
  packed.resize(n);
  for (size_t i = 0; i < n; ++i)
    packed[i] = ((records[i].key - lo) >> zeros) << 8 | records[i].mask;
  radix_sort(packed, 8, bits, scratch);
  for (size_t i = 0; i < n; ++i) {
    records[i] = {((packed[i] >> 8) << zeros) + lo, static_cast<uint8_t>(packed[i])};
  }
}

// The words sorted on the bits their offsets differ in: below the lowest
// set bit of them all every offset is zero, so the sort starts there.
void NodePixels::sort_words() {
  const uint64_t all = words_.take(&packed_) >> 8;
  if (all == 0) return;  // one offset, or none
  const int low = std::countr_zero(all);
  radix_sort(packed_, 8 + low, std::bit_width(all) - low, scratch_);
}

// Keys too wide for words: records, sorted by sort_records (std::sort,
// unless the keys' own span is narrower than the one allowed for).
void NodePixels::sort_hashed() {
  records_.resize(hash_.size());
  for (size_t i = 0; i < hash_.size(); ++i) records_[i] = {hash_.key_at(i), hash_.mask_at(i)};
  sort_records(records_, packed_, scratch_);
}

}  // namespace weaver
