// The aggregate table: a summary of the leaves inside each coarse octant,
// for pictures of the whole mesh at any scale (the map tiles of `weaver
// serve`): where thousands of elements fall in one pixel, the pixel shows
// the octant of the pixel's size around it, as the least Vs, the finest
// level or the mean of a field over the leaves inside it.
//
// One record per octant of levels 0 to F that holds at least one leaf
// strictly inside it (over all levels, at most a seventh as many as the
// leaves): an octant that is a leaf, lies inside a leaf or lies outside the
// domain has none.  F is the finest level whose records, estimated from
// the leaves per level, number at most AggregateOptions::max_records.
// Keyed by the octant's key, so in key order (preorder).  The metadata
// names the finest level with records (";finest=F").
// Payload, little-endian, the schema stored with the table:
//   leaves:u64            leaves inside
//   level_min:u8, level_max:u8   their coarsest and finest levels
//   F_min:f32, F_max:f32, F_mean:f32   for each field F of the octant table
//                         (vp, vs, rho, and qp, qs where present); the mean
//                         is weighted by volume
// The records are built by one scan of the octant table in key order, each
// leaf added to its finest open octant and each octant's summary added to
// its parent's when it closes.  A level's octants close in key order, but
// after the finer ones inside them, so each level goes to a table file of
// its own, and these are merged into the table by sorted append: memory
// does not grow with the mesh.  Derived from the octant table: replacing
// the octants drops it (db/database.cc).  `weaver verify` computes it again
// and compares, record by record.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "db/aggregate_table.h"
#include "schema/status.h"
#include "util/memory_budget.h"
#include "util/progress.h"

namespace weaver {

class BTree;
struct Field;

// The fields summarised, in record order (those the octant table has).
inline constexpr std::array<const char*, 5> kAggregateFields = {"vp", "vs", "rho", "qp", "qs"};

// One octant's summary.
struct Aggregate {
  uint64_t leaves = 0;
  int level_min = 0, level_max = 0;
  std::array<float, 5> min{}, max{}, mean{};  // by kAggregateFields' index
};

// A summary in the making: leaves, or the summaries of parts, added one by
// one.  The mean is weighted by volume.
class SummaryBuilder {
 public:
  SummaryBuilder() { reset(); }
  void reset();
  // A leaf of `level` with its fields (kAggregateFields' first `fields`).
  void add_leaf(int level, const float* values, int fields);
  void add(const SummaryBuilder& part, int fields);
  uint64_t leaves() const { return leaves_; }
  Aggregate result(int fields) const;

 private:
  uint64_t leaves_ = 0;
  int level_min_ = 0, level_max_ = 0;
  std::array<float, 5> min_{}, max_{};
  std::array<double, 5> sum_{};
  double volume_ = 0;
};

// The fields of kAggregateFields an octant table's payloads carry (0, 3 or
// 5), read as floats.
class LeafFields {
 public:
  explicit LeafFields(BTree& octants);
  int count() const { return count_; }
  void read(const std::byte* payload, float* out) const;

 private:
  int count_ = 0;
  std::array<const Field*, 5> field_{};
};

// An octant's summary as a batch lookup answers it.
struct AggregateHit {
  bool found = false;  // false: the octant is a leaf, lies inside one or outside the domain
  Aggregate a;
};

// How the records of a table are laid out: which fields they carry.
class AggregateLayout {
 public:
  // For an octant table with (or without) material and Q.
  AggregateLayout(bool material, bool q);
  // For a stored aggregate table: from its schema; Corruption when the
  // schema is not one this layout writes.
  static Status of_table(BTree& table, AggregateLayout* out);
  int fields() const { return fields_; }
  uint32_t record_size() const { return 10 + 12 * uint32_t(fields_); }
  std::string schema_text() const;
  void encode(const Aggregate& a, std::byte* out) const;
  void decode(const std::byte* in, Aggregate* a) const;

 private:
  int fields_ = 0;  // 0, 3 or 5: the first n of kAggregateFields
};

struct AggregateOptions {
  MemoryBudget memory;
  // The table keeps levels 0 to the finest whose records number at most
  // this many (by an estimate from the leaves per level); 0: a 64th of the
  // leaves, or 4M if that is more.
  uint64_t max_records = 0;
  ProgressFn progress;  // leaves scanned, fraction of the octant table
};

struct AggregateReport {
  uint64_t leaves = 0;   // scanned
  uint64_t records = 0;  // written
  int finest = -1;       // the finest level with records (-1: none)
  uint64_t bytes = 0;    // the table's file
};

// Builds the aggregate table of database db_dir from its octant table and
// commits it (replacing an older one).  A failure leaves the database as it
// was.
Status build_aggregates(const std::string& db_dir, const AggregateOptions& o,
                        AggregateReport* report);

// The finest level (from the table's metadata), -1 when it has none.
int aggregate_finest(BTree& table);

// Verify: computes the summaries again from the octant table and
// compares them with `table` record by record; the first max_problems
// differences go to *problems, each naming the octant.
Status check_aggregates(BTree& octants, BTree& table, size_t max_problems,
                        std::vector<std::string>* problems);

}  // namespace weaver
