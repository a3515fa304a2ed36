// One memory budget (`--memory`), and the named shares a stage cuts from it.
//
// A command builds one MemoryBudget from --memory and hands it to each stage
// it runs (stages run one after another, so each gets the whole budget).  A
// stage lays out all the memory it will hold in a MemoryPlan: one named
// share per buffer pool, hash table, spill cap or sort buffer, each taken as
// a fraction of the budget, with the reason for the fraction written next to
// it.  tests/memory_budget_test.cc checks that every stage's shares add up
// to no more than the budget, for budgets from the smallest --memory up.
//
// What the shares do not count: a B+tree's buffer pool keeps at least
// BufferPool::kMinFrames pages and its write staging buffer (512 KiB with 4
// KiB pages) whatever its share, so at the smallest budgets pools exceed it;
// and code, stacks and allocator slack come on top; tests/memory_bound_test.cc
// measures the resident size a user sees.
#pragma once

#include <algorithm>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace weaver {

class MemoryBudget {
 public:
  // --memory when the option is absent.
  static constexpr uint64_t kDefaultBytes = 256ull << 20;
  // The smallest --memory a command accepts.
  static constexpr uint64_t kMinBytes = 1ull << 20;

  constexpr MemoryBudget() = default;
  constexpr explicit MemoryBudget(uint64_t bytes) : bytes_(bytes) {}
  constexpr uint64_t bytes() const { return bytes_; }

 private:
  uint64_t bytes_ = kDefaultBytes;
};

struct MemoryShare {
  std::string name;
  uint64_t bytes = 0;
};

class MemoryPlan {
 public:
  static constexpr uint64_t kNoCap = std::numeric_limits<uint64_t>::max();

  explicit MemoryPlan(MemoryBudget budget) : budget_(budget) {}

  // Takes num/den of the budget, at most cap bytes, and records it by name.
  uint64_t take(const char* name, uint64_t num, uint64_t den, uint64_t cap = kNoCap) {
    return record(name, std::min(budget_.bytes() / den * num, cap));
  }
  // Takes what the earlier shares left.
  uint64_t take_rest(const char* name) {
    return record(name, budget_.bytes() - std::min(taken_, budget_.bytes()));
  }
  // Hands num/den of the budget to a stage run from within this one (with
  // a plan of its own); recorded as one share.
  MemoryBudget take_budget(const char* name, uint64_t num, uint64_t den) {
    return MemoryBudget(take(name, num, den));
  }
  // Records a share whose size the caller worked out (e.g. n equal pools).
  uint64_t record(const char* name, uint64_t bytes) {
    shares_.push_back({name, bytes});
    taken_ += bytes;
    return bytes;
  }

  MemoryBudget budget() const { return budget_; }
  uint64_t taken() const { return taken_; }
  const std::vector<MemoryShare>& shares() const { return shares_; }

 private:
  MemoryBudget budget_;
  uint64_t taken_ = 0;
  std::vector<MemoryShare> shares_;
};

}  // namespace weaver
