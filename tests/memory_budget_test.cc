// Every command's memory shares add up to no more than its --memory budget,
// for budgets from the smallest --memory up, and none is empty.
#include "util/memory_budget.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "balance/balance.h"
#include "construct/construct.h"
#include "export/export.h"
#include "extract/extract.h"
#include "import/import.h"
#include "query/explorer.h"
#include "verify/verify.h"

namespace weaver {
namespace {

const std::vector<uint64_t> kBudgets = {
    MemoryBudget::kMinBytes, (2ull << 20) + 3, 16ull << 20, MemoryBudget::kDefaultBytes,
    (1ull << 30) + 12345,    7ull << 30,       64ull << 30, 1ull << 40};

std::string describe(const MemoryPlan& plan) {
  std::string s = std::to_string(plan.budget().bytes()) + " bytes:";
  for (const MemoryShare& share : plan.shares()) {
    s += " " + share.name + "=" + std::to_string(share.bytes);
  }
  return s;
}

// The shares fit the budget, and each gets something.
void expect_fits(const MemoryPlan& plan) {
  EXPECT_LE(plan.taken(), plan.budget().bytes()) << describe(plan);
  EXPECT_FALSE(plan.shares().empty());
  for (const MemoryShare& share : plan.shares()) {
    EXPECT_GT(share.bytes, 0u) << share.name << " in " << describe(plan);
  }
}

TEST(MemoryBudgetTest, ExtractSharesFitEveryBudgetAndThreadCount) {
  for (const uint64_t bytes : kBudgets) {
    for (const int threads : {1, 2, 3, 8, 256}) {
      ExtractOptions o;
      o.memory = MemoryBudget(bytes);
      o.threads = threads;
      const ExtractMemory m(o);
      expect_fits(m.plan);
      // The per-worker fields, times the workers, are within their shares.
      uint64_t per_worker = (m.bucket + m.worker_pool) * threads;
      EXPECT_LE(m.octant_pool + m.node_pool + m.spill + per_worker + m.in_flight, bytes);
      EXPECT_EQ(m.search_store, 0u);
    }
    for (const auto store : {ExtractOptions::Store::kBTree, ExtractOptions::Store::kLsm}) {
      ExtractOptions o;
      o.memory = MemoryBudget(bytes);
      o.algorithm = ExtractOptions::Algorithm::kSearch;
      o.store = store;
      const ExtractMemory m(o);
      expect_fits(m.plan);
      EXPECT_GT(m.search_store, 0u);
      EXPECT_EQ(m.bucket, 0u);
    }
  }
}

TEST(MemoryBudgetTest, BalanceSharesFitEveryBudget) {
  for (const uint64_t bytes : kBudgets) {
    const BalanceMemory m{MemoryBudget(bytes)};
    expect_fits(m.plan);
    // 3 spools a level for levels 0..kMaxLevel, each with its buffer.
    EXPECT_LE(m.leaf_pool + m.output_pool + 3 * (kMaxLevel + 1) * m.spool_buffer + m.parent_chunk +
                  m.candidate_sort,
              bytes);
    EXPECT_GT(m.spool_buffer, 0u);
  }
}

TEST(MemoryBudgetTest, VerifySharesAndItsBalanceCheckFitEveryBudget) {
  for (const uint64_t bytes : kBudgets) {
    const VerifyMemory m{MemoryBudget(bytes)};
    expect_fits(m.plan);
    const BalanceMemory check(m.balance_check);
    expect_fits(check.plan);
    EXPECT_LE(m.table_pool + m.octant_pool + m.node_pool + check.plan.taken(), bytes);
  }
}

// A balanced construct from a model database pools its subtrees' rooms
// from 256M on two threads (others from 512M), never below 256M, and its
// plan then counts the balance's buffers: room for four even shares of
// leaves a worker.
TEST(MemoryBudgetTest, ConstructFromAModelDatabaseCountsTheBalanceWhereItPools) {
  for (const uint64_t bytes : kBudgets) {
    for (const int threads : {1, 2, 3, 8}) {
      const ConstructMemory m(MemoryBudget(bytes), threads, true);
      expect_fits(m.plan);
      EXPECT_EQ(m.balance > 0, m.pooled) << describe(m.plan);
      EXPECT_LE(m.balance, bytes / 16 * 3) << describe(m.plan);
    }
  }
  const ConstructMemory db(MemoryBudget(), 2, true);
  const ConstructMemory analytic(MemoryBudget(), 2, false);
  EXPECT_TRUE(db.pooled);
  EXPECT_FALSE(analytic.pooled);
  EXPECT_EQ(analytic.balance, 0u);
  // 4 even shares of 2^17 leaves a worker, 48 bytes each.
  EXPECT_EQ(db.balance, 2 * 4 * (uint64_t{1} << 17) * 48);
  EXPECT_FALSE(ConstructMemory(MemoryBudget(128ull << 20), 2, true).pooled);
  EXPECT_FALSE(ConstructMemory(MemoryBudget(128ull << 20), 1, true).pooled);
  EXPECT_TRUE(ConstructMemory(MemoryBudget(256ull << 20), 1, true).pooled);
  EXPECT_GT(ConstructMemory(MemoryBudget(256ull << 20), 1, true).balance, 0u);
  EXPECT_FALSE(ConstructMemory(MemoryBudget(128ull << 20), 1, false).pooled);
  EXPECT_TRUE(ConstructMemory(MemoryBudget(512ull << 20), 2, false).pooled);
}

TEST(MemoryBudgetTest, ConstructImportExportAndQuerySharesFitEveryBudget) {
  for (const uint64_t bytes : kBudgets) {
    const MemoryBudget budget(bytes);
    expect_fits(ConstructMemory(budget).plan);
    const ImportMemory import(budget);
    expect_fits(import.plan);
    EXPECT_LE(2 * import.table_pool + ImportMemory::kMaxRuns * import.run_pool + import.memtable,
              bytes);
    expect_fits(ExportMemory(budget).plan);
    expect_fits(ExplorerMemory(budget).plan);
  }
}

TEST(MemoryBudgetTest, PlanTakesFractionsWithCapsAndTheRest) {
  MemoryPlan plan(MemoryBudget(1000));
  EXPECT_EQ(plan.take("quarter", 1, 4), 250u);
  EXPECT_EQ(plan.take("capped", 1, 2, 100), 100u);
  EXPECT_EQ(plan.take_budget("nested", 1, 10).bytes(), 100u);
  EXPECT_EQ(plan.take_rest("rest"), 550u);
  EXPECT_EQ(plan.taken(), 1000u);
  EXPECT_EQ(plan.take_rest("nothing left"), 0u);
  ASSERT_EQ(plan.shares().size(), 5u);
  EXPECT_EQ(plan.shares()[1].name, "capped");
  EXPECT_EQ(MemoryBudget().bytes(), MemoryBudget::kDefaultBytes);
}

}  // namespace
}  // namespace weaver
