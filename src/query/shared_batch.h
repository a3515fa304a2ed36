// A batch of points answered by several Explorers of one database, a thread
// each: the batch's keys are cut into as many runs of about equal counts
// as there are Explorers, by key range, and each Explorer sorts and walks
// one run, so that a leaf page is read by one of them only (split by input
// order, each would read most pages of a large mesh for random points),
// and the sorts run at once rather than one before the walks.  Used by
// `weaver query --points`, `weaver serve` and the library API.
#pragma once

#include <cstddef>
#include <vector>

#include "query/explorer.h"

namespace weaver {

class SharedBatch {
 public:
  // Below this many points a batch is answered by the first Explorer alone:
  // a thread's start costs more than it saves.
  static constexpr size_t kParallelPoints = 16384;

  // explorers[0] answers alone, or with the others for a large batch; all of
  // them open on the same committed state.
  explicit SharedBatch(std::vector<Explorer*> explorers) : explorers_(std::move(explorers)) {}

  // out[i] answers p[i]; every entry of out is written.
  Status locate(const Coord* p, size_t n, PointHit* out);
  Status node_at(const Coord* p, size_t n, NodeHit* out);

  // How many Explorers a batch of n points is shared among.
  size_t parts(size_t n) const { return n >= kParallelPoints ? explorers_.size() : 1; }

 private:
  // A small batch goes to the first Explorer's own batch call (`alone`);
  // a large one is cut into runs, each sorted and walked (`walk`) by one.
  template <typename Hit, typename Alone, typename Walk>
  Status run(const Coord* p, size_t n, bool nodes, Hit* out, Alone alone, Walk walk);
  // Moves keyed_ into scratch_ as `parts` runs of keys, each run's keys all
  // below the next run's; starts[i] is where run i begins (starts[parts]:
  // the end).
  void cut_runs(size_t parts, std::vector<size_t>* starts);

  std::vector<Explorer*> explorers_;
  // Kept from batch to batch: the keyed points and the sort's other buffer.
  std::vector<KeyedPoint> keyed_, scratch_;
  std::vector<uint32_t> bins_;  // cut_runs' histogram
};

}  // namespace weaver
