#include "query/shared_batch.h"

#include <algorithm>
#include <bit>

#include "util/huge_pages.h"
#include "util/parallel.h"
#include "util/radix_sort.h"

namespace weaver {
namespace {

uint64_t key_of(const KeyedPoint& k) { return k.first; }

// The histogram's bins: the keys' range in at most this many.
constexpr int kBinBits = 16;

}  // namespace

void SharedBatch::cut_runs(size_t parts, std::vector<size_t>* starts) {
  const size_t m = keyed_.size();
  uint64_t lo = UINT64_MAX, hi = 0;
  for (const KeyedPoint& k : keyed_) lo = std::min(lo, k.first), hi = std::max(hi, k.first);
  const int shift = std::max(0, int(std::bit_width(hi - lo)) - kBinBits);
  bins_.assign((size_t{1} << kBinBits) + 1, 0);
  for (const KeyedPoint& k : keyed_) ++bins_[(k.first - lo) >> shift];
  // Run i takes the bins from the first whose keys begin past i/parts of
  // the batch (a bin is never split: its keys share their high bits).
  std::vector<uint64_t> first_bin(parts + 1, bins_.size());
  first_bin[0] = 0;
  size_t before = 0, run = 1;
  for (size_t b = 0; b < bins_.size() && run < parts; ++b) {
    while (run < parts && before >= m * run / parts) first_bin[run++] = b;
    before += bins_[b];
  }
  auto run_of = [&](uint64_t key) {
    const uint64_t b = (key - lo) >> shift;
    size_t r = 0;
    while (r + 1 < parts && b >= first_bin[r + 1]) ++r;
    return r;
  };
  starts->assign(parts + 1, 0);
  for (const KeyedPoint& k : keyed_) ++(*starts)[run_of(k.first) + 1];
  for (size_t r = 0; r < parts; ++r) (*starts)[r + 1] += (*starts)[r];
  std::vector<size_t> at(starts->begin(), starts->end() - 1);
  reserve_huge(scratch_, m);
  scratch_.resize(m);
  for (const KeyedPoint& k : keyed_) scratch_[at[run_of(k.first)]++] = k;
}

template <typename Hit, typename Alone, typename Walk>
Status SharedBatch::run(const Coord* p, size_t n, bool nodes, Hit* out, Alone alone, Walk walk) {
  const size_t parts = this->parts(n);
  if (parts == 1) return alone(*explorers_[0]);
  std::fill(out, out + n, Hit{});
  Explorer::key_batch(p, n, nodes, &keyed_);
  std::vector<size_t> starts;
  cut_runs(parts, &starts);
  // Each run sorted where it lies, keyed_ its other buffer.
  return run_shares(int(parts), [&](int i) {
    const size_t from = starts[size_t(i)], count = starts[size_t(i) + 1] - from;
    const KeyedPoint* sorted =
        radix_sort_buffers(scratch_.data() + from, keyed_.data() + from, count, key_of);
    return walk(*explorers_[size_t(i)], sorted, count);
  });
}

Status SharedBatch::locate(const Coord* p, size_t n, PointHit* out) {
  return run(
      p, n, false, out, [&](Explorer& e) { return e.locate_batch(p, n, out); },
      [out](Explorer& e, const KeyedPoint* run, size_t count) {
        return e.locate_sorted(run, count, out);
      });
}

Status SharedBatch::node_at(const Coord* p, size_t n, NodeHit* out) {
  return run(
      p, n, true, out, [&](Explorer& e) { return e.node_at_batch(p, n, out); },
      [out](Explorer& e, const KeyedPoint* run, size_t count) {
        return e.node_at_sorted(run, count, out);
      });
}

}  // namespace weaver
