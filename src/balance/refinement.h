// The refinement writer of balance: every leaf of the input is written in
// Z-order by sorted append, split just enough that each required octant
// strictly inside it (closure.h) is resolved.  A split leaf's children copy
// its payload, and then a callback may fill in their own material.
#pragma once

#include <cstddef>
#include <functional>
#include <memory>

#include "balance/balance.h"
#include "balance/balance_progress.h"
#include "schema/octant.h"
#include "schema/status.h"
#include "sort/key_tag.h"
#include "storage/btree.h"
#include "util/memory_budget.h"

namespace weaver {

class VelocityModel;

// Fills the payload of new leaf o (holding a copy of its parent's) with o's
// own values, e.g. the material of a velocity model at its centre.  False:
// o is no leaf of the output (air over a carved mesh's ground).
using FillPayload = std::function<bool(const Octant& o, std::byte* payload)>;

// The material of new leaves of a table built from a model (the one its
// metadata names, opened into *model within `memory` for `threads`
// threads): the model's vp, vs and rho (and qp, qs) at the leaf's centre,
// where the schema has those fields; empty for other tables, whose new
// leaves keep their parent's values.  A model database named by its
// identity (modeldb/model_identity.h) is looked for in model_dirs; not
// finding it is an error naming it.  A table built under a ground (its
// metadata names the surface, read within `surface`) has its new leaves
// carved as construct carves: their solid fraction set, the model asked
// through the ground, and those wholly above it no leaves at all.
Status model_material_fill(const TableOptions& table, const std::vector<std::string>& model_dirs,
                           MemoryBudget memory, MemoryBudget surface, int threads,
                           std::unique_ptr<VelocityModel>* model, FillPayload* fill);

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
