// The refinement writer of balance: every leaf of the input is written in
// Z-order by sorted append, split just enough that each required octant
// strictly inside it (closure.h) is resolved.  A split leaf's children copy
// its payload, and then a callback may fill in their own material.
#pragma once

#include <cstddef>
#include <functional>

#include "balance/balance.h"
#include "balance/balance_progress.h"
#include "schema/octant.h"
#include "schema/status.h"
#include "sort/key_tag.h"
#include "storage/btree.h"

namespace weaver {

// Fills the payload of new leaf o (holding a copy of its parent's) with o's
// own values, e.g. the material of a velocity model at its centre.
using FillPayload = std::function<void(const Octant& o, std::byte* payload)>;

// Writes the refinement of `leaves` by `required` (key order, as from
// Closure::required) into `out`, which has the payload size of `leaves`.
// fill may be empty.  Counts go to r: output_leaves, split, levels.  With
// threads > 1 the output's pages are encoded and written on a thread of
// their own, beside the reading and splitting.
// Only the input leaves with keys in [keep_from, keep_to) are written.
Status write_refinement(BTree& leaves, KeyTagSource& required, const FillPayload& fill, BTree& out,
                        int threads, BalanceProgress* progress, BalanceResult* r,
                        uint64_t keep_from = 0, uint64_t keep_to = UINT64_MAX);

}  // namespace weaver
