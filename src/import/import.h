// `weaver import`: octant text in any order into the octant table, within a
// memory budget.  Validates every line (format, range, alignment).  Octants
// in key order are appended straight to the table; from the first one out
// of order on, the rest go into an LSM store (storage/lsm.h) with their line
// numbers, and the table so far and the LSM are merged into the final table.
// Duplicate and overlapping octants are rejected naming both lines.  The
// table is committed only if all of it is good.
#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include "db/octant_table.h"
#include "schema/status.h"
#include "util/memory_budget.h"
#include "util/progress.h"

namespace weaver {

struct ImportOptions {
  MemoryBudget memory;
  // The units of the new table.  Those not given keep the values of the
  // octant table being replaced (or the defaults when there is none).
  Units units;
  bool tick_given = false, origin_given = false;
  // Packed leaf pages (storage/packed_leaf.h); false writes plain ones.
  bool packed = true;
  // Called now and then with (phase, items done); may be empty.
  // Octants read (no fraction: the text's line count is not known ahead).
  ProgressFn progress;
};

// Where import's memory goes: the shares of options.memory.
struct ImportMemory {
  explicit ImportMemory(MemoryBudget budget);

  MemoryPlan plan;
  uint64_t table_pool = 0;  // each of the two tables written by sorted append
  uint64_t run_pool = 0;    // each of the LSM's runs (at most kMaxRuns at once)
  uint64_t memtable = 0;    // the LSM's memtable: the octants that came out of order
  static constexpr uint64_t kMaxRuns = 16;
};

struct ImportResult {
  uint64_t octants = 0;
  uint64_t runs_spilled = 0;  // LSM runs written (flushes and merges)
  uint64_t table_bytes = 0;
};

Status import_octants(const std::string& db_dir, const std::string& text_path,
                      const ImportOptions& options, ImportResult* result);

}  // namespace weaver
