#include "query/shared_batch.h"

#include <algorithm>

#include "util/parallel.h"

namespace weaver {

template <typename Hit, typename Walk>
Status SharedBatch::run(const Coord* p, size_t n, bool nodes, Hit* out, Walk walk) {
  std::fill(out, out + n, Hit{});
  Explorer::sort_batch(p, n, nodes, &order_, &scratch_);
  const size_t m = order_.size(), parts = this->parts(n);
  return run_shares(int(parts), [&](int i) {
    const size_t from = m * size_t(i) / parts, to = m * size_t(i + 1) / parts;
    return walk(*explorers_[size_t(i)], order_.data() + from, to - from);
  });
}

Status SharedBatch::locate(const Coord* p, size_t n, PointHit* out) {
  return run(p, n, false, out, [out](Explorer& e, const KeyedPoint* run, size_t count) {
    return e.locate_sorted(run, count, out);
  });
}

Status SharedBatch::node_at(const Coord* p, size_t n, NodeHit* out) {
  return run(p, n, true, out, [out](Explorer& e, const KeyedPoint* run, size_t count) {
    return e.node_at_sorted(run, count, out);
  });
}

}  // namespace weaver
