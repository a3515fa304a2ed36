// Construct and balance of the basin model's mesh, as the benchmarks run
// them (in a child process each, through bench_util.h's run_in_child).
#pragma once

#include <cstdint>
#include <string>

#include "balance/balance.h"
#include "construct/construct.h"
#include "util/memory_budget.h"

namespace weaver::bench {

// Constructs the basin at freq into db (replacing it); its leaves in *leaves.
inline bool construct_basin(const std::string& db, double freq, int threads, uint64_t memory,
                            uint64_t* leaves) {
  ConstructOptions o;
  o.model = "basin";
  o.freq = freq;
  o.threads = threads;
  o.memory = MemoryBudget(memory);
  ConstructPlan plan;
  ConstructResult r;
  if (!construct_octree(db, o, &plan, &r).ok()) return false;
  *leaves = r.elements;
  return true;
}

// Balances db; the leaves before and after.
inline bool balance_db(const std::string& db, uint64_t memory, uint64_t* input, uint64_t* output) {
  BalanceOptions o;
  o.memory = MemoryBudget(memory);
  BalanceResult r;
  if (!balance_octree(db, o, &r).ok()) return false;
  *input = r.input_leaves;
  *output = r.output_leaves;
  return true;
}

}  // namespace weaver::bench
