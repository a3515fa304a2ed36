// `weaver query DB locate|material|node-at --points FILE|-`: millions of
// points, one "x y z" per line (spaces, tabs or commas between; blank lines
// and lines starting with '#' skipped), answered a batch at a time by the
// Explorer and written one row per point in input order.  A malformed line
// gets a row with status "bad" and a message naming its line; a point
// outside the domain gets a row with status "outside": never a silent drop.
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "cli/query_output.h"
#include "query/explorer.h"
#include "schema/status.h"

namespace weaver::cli {

enum class PointQuery { kLocate, kMaterial, kNodeAt };

struct PointBatchOptions {
  PointQuery query = PointQuery::kLocate;
  OutputMode mode = OutputMode::kText;  // text and table print space-separated columns
  bool metres = false;                  // input and lengths in metres, not ticks
  bool one = false;  // one point asked on the command line: JSON prints an object
  // More Explorers on the same committed state as the one asked: a large
  // batch splits its lookups and its rows among them, a thread each.
  std::vector<Explorer*> helpers;
  // Points answered at a time (0: what the Explorers' shares for a batch
  // hold, kBatchPointBytes each): more for a caller that sets memory aside.
  size_t batch_points = 0;
};

// What a point of a batch holds while it is answered: its coordinate (12
// bytes), its metres (24), its answer (40) and its sort pair and the sort's
// scratch (32), with margin.
inline constexpr size_t kBatchPointBytes = 128;

struct PointBatchResult {
  uint64_t points = 0;     // rows written
  uint64_t bad_lines = 0;  // rows with status "bad"
  uint64_t missed = 0;     // outside the domain / no node there
};

// Reads `in` (named `name` in messages, which go to err) to its end.  Fails
// only on I/O errors and on a database error; bad lines are counted.
Status run_point_batch(Explorer& ex, std::FILE* in, const std::string& name,
                       const PointBatchOptions& o, std::FILE* out, std::FILE* err,
                       PointBatchResult* result);

}  // namespace weaver::cli
