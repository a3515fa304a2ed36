// Construct and balance of the basin model's mesh, as the benchmarks run
// them (in a child process each, through bench_util.h's run_in_child).
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>

#include "balance/balance.h"
#include "bench_util.h"
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

// The basin's mesh at freq Hz in /tmp/weaver-tile-bench, built by `weaver
// mesh` unless it is there already (the serve benchmarks share it); "" if
// it cannot be built.
inline std::string basin_mesh(double freq) {
  const std::string dir = "/tmp/weaver-tile-bench";
  std::filesystem::create_directories(dir);
  const std::string db = dir + "/basin-" + fmt(freq) + "Hz.db";
  uint64_t peak = 0;
  if (std::filesystem::exists(db + "/MANIFEST")) return db;
  return run_program(
             {WEAVER_BINARY, "mesh", db, "--model", "basin", "--freq", fmt(freq), "--quiet"}, &peak)
                 .empty()
             ? ""
             : db;
}

}  // namespace weaver::bench
