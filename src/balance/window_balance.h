// Balance in windows: the input leaves cut into runs of consecutive keys,
// each balanced in memory, on worker threads, against the leaves of its
// insulation layer, and written in key order by sorted append.
//
// A leaf o's refinement depends only on the input leaves that meet the
// 3 x 3 x 3 block of o-sized octants around it (construct/subtree_balance.h
// gives the argument: every chain of requirements that ends inside o
// starts there).  So a window reads its own leaves, then the leaves
// outside it that meet the blocks of its leaves near its edge (most
// leaves' blocks lie inside the window: the coarsest aligned octant
// holding a leaf inside the window answers for them), ripples them all
// (util/local_ripple.h) and splits its own leaves just enough.  The table
// is read once, plus the layers; nothing goes through a sort on disk.
//
// A window whose layer, ripple or refinement outgrows its share of memory
// is cut in two, and so on.  A short window that still does (a very coarse
// leaf beside very many fine ones), or a layer that outweighs its window
// many times, gives up: *fitted is false, `out` holds a part, and the
// caller balances by the closure instead.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "balance/balance.h"
#include "balance/refinement.h"
#include "db/database.h"
#include "schema/status.h"
#include "storage/btree.h"

namespace weaver {

struct WindowOptions {
  // One handle on the input table for each worker thread (one: this thread
  // works alone).
  std::vector<BTree*> readers;
  uint64_t memory = 0;         // for all the windows in flight together
  uint64_t window_leaves = 0;  // tests: windows at most this long (0: as memory allows)
  ProgressFn progress;         // leaves read, fraction done
  // Only the leaves of ranks [first_leaf, end_leaf) and their refinement
  // are written (one rank's part of weaver-mpi balance); the layers come
  // from the whole table all the same.
  uint64_t first_leaf = 0, end_leaf = UINT64_MAX;
  // Give up (*fitted false) when a whole window of at least layer_window
  // leaves has a layer more than layer_limit times as long (0: never), or
  // when a window of at most least_cut leaves does not fit.
  double layer_limit = 0;
  uint64_t layer_window = 4096, least_cut = 4096;
  // One window of every leaf, with no layer: read and rippled once (the
  // ripple's levels shared between the threads), then refined in blocks on
  // every reader's thread; *fitted is false if the memory does not hold
  // it.  Where the layers of many windows outweigh them (random
  // refinement), one window of a table that fits is the least work.
  bool one_window = false;
};

// The windows' options as balance's ask (its algorithm, memory share and
// limits), and a handle on db's octant table for each thread beyond
// `leaves` (kept in *more).
Status window_options(Database& db, BTree& leaves, const BalanceOptions& o,
                      const BalanceMemory& memory, std::vector<std::unique_ptr<BTree>>* more,
                      WindowOptions* wo);

Status balance_in_windows(const WindowOptions& options, const FillPayload& fill, BTree& out,
                          BalanceResult* r, bool* fitted);

// Whether one window of every leaf of `leaves` may fit in `memory` (by an
// estimate a leaf; the ripple's own measure decides in the end).
bool one_window_may_fit(const BTree& leaves, uint64_t memory);

}  // namespace weaver
