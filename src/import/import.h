// `weaver import`: octant text in any order into the octant table, within a
// memory budget.  Validates every line (format, range, alignment), then
// sorts out of core and rejects duplicate and overlapping octants while
// appending in key order.  The table is committed only if all of it is good.
#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include "db/octant_table.h"
#include "schema/status.h"

namespace weaver {

struct ImportOptions {
  uint64_t memory_bytes = 256ull << 20;
  Units units;
  // Called now and then with (phase, items done); may be empty.
  std::function<void(const char*, uint64_t)> progress;
};

struct ImportResult {
  uint64_t octants = 0;
  uint64_t runs_spilled = 0;
  uint64_t table_bytes = 0;
};

Status import_octants(const std::string& db_dir, const std::string& text_path,
                      const ImportOptions& options, ImportResult* result);

}  // namespace weaver
