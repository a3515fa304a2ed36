#include "query/aggregates.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <memory>

#include "db/database.h"
#include "db/leaf_window.h"
#include "db/octant_table.h"
#include "mesh/mesh_reader.h"
#include "schema/octant.h"
#include "storage/btree.h"

namespace weaver {
namespace {

// An open octant of the scan: its key and what it holds so far.
struct Open {
  uint64_t key = 0;
  SummaryBuilder sum;
  void reset(uint64_t k) { key = k, sum.reset(); }
};

// The finest level whose octants share the one holding a and the one
// holding b (-1 when not even the root does, which cannot happen).
int common_level(uint64_t a, uint64_t b) {
  if (a == b) return kMaxLevel;
  const int bits = 64 - __builtin_clzll(a ^ b);  // the highest differing bit, + 1
  return kMaxLevel - (bits + 2) / 3;
}

// The scan: leaves in key order in, each closed octant of level <= finest
// out (post-order: children before their parent), through emit.
class Summarizer {
 public:
  using Emit = std::function<Status(int level, const Open& o)>;
  Summarizer(int finest, int fields, Emit emit) : finest_(finest), fields_(fields), emit_(emit) {}

  Status add(uint64_t key, const float* values) {
    const uint64_t m = octant_key_morton(key);
    const int level = octant_key_level(key);
    const int top = std::min(level - 1, finest_);  // its finest octant here
    const int keep = std::min({open_, common_level(m, last_m_), top});
    WEAVER_RETURN_IF_ERROR(close_to(keep));
    for (int l = open_ + 1; l <= top; ++l) stack_[l].reset(octant_key_ancestor(key, l));
    open_ = std::max(open_, top);
    last_m_ = m;
    if (top < 0) return Status::Ok();
    stack_[top].sum.add_leaf(level, values, fields_);
    return Status::Ok();
  }
  Status finish() { return close_to(-1); }

 private:
  // Closes the open octants finer than `keep`, each into its parent.
  Status close_to(int keep) {
    for (; open_ > keep; --open_) {
      WEAVER_RETURN_IF_ERROR(emit_(open_, stack_[open_]));
      if (open_ > 0) stack_[open_ - 1].sum.add(stack_[open_].sum, fields_);
    }
    return Status::Ok();
  }
  int finest_, fields_;
  Emit emit_;
  std::array<Open, kMaxLevel> stack_;
  int open_ = -1;  // levels 0..open_ are open
  uint64_t last_m_ = 0;
};

// Runs the summarizer over the whole octant table.
Status scan_octants(BTree& octants, Summarizer& s, const ProgressFn& progress) {
  const LeafFields reader(octants);
  BTreeCursor c;
  WEAVER_RETURN_IF_ERROR(octants.seek_cursor(0, &c));
  const uint64_t total = octants.size();
  float values[5] = {};
  for (uint64_t n = 0; c.valid(); ++n) {
    reader.read(c.payload(), values);
    WEAVER_RETURN_IF_ERROR(s.add(c.key(), values));
    if (progress && (n & 0xfffff) == 0)
      progress(n, double(n) / double(std::max<uint64_t>(total, 1)));
    WEAVER_RETURN_IF_ERROR(c.next());
  }
  return s.finish();
}

// The levels the table keeps: 0 to the finest whose records, estimated from
// the leaves per level, number at most max_records.  An octant of level l
// with leaves inside holds their volume, so a level has about sum over k > l
// of n_k / 8^(k - l) records (exactly, where the domain has no holes finer
// than l), at most 8^l.
int finest_that_fits(const LevelCounts& n, uint64_t max_records) {
  double total = 0;
  for (int l = 0; l < kMaxLevel; ++l) {
    double at = 0;
    for (int k = l + 1; k <= kMaxLevel; ++k) at += double(n[k]) / std::ldexp(1.0, 3 * (k - l));
    total += std::min(std::ceil(at), std::ldexp(1.0, 3 * l));
    if (total > double(max_records)) return l - 1;
  }
  return kMaxLevel - 1;
}

// A level's records arrive in key order, a coarser level's after the finer
// ones inside them: each level goes to a table file of its own (packed, as
// the final one), and these are merged by sorted append at the end.  They
// are deleted however the build ends (a crash leaves them to the next
// writer, as leftovers).
class LevelFiles {
 public:
  explicit LevelFiles(Database& db) : db_(db), tree_(kMaxLevel), file_(kMaxLevel) {}
  ~LevelFiles() {
    for (int l = 0; l < kMaxLevel; ++l) {
      tree_[l].reset();
      if (!file_[l].empty()) db_.abandon(file_[l]);
    }
  }
  Status create(int levels, const TableOptions& t, uint64_t pool) {
    for (int l = 0; l < levels; ++l) {
      WEAVER_RETURN_IF_ERROR(db_.create_table(kAggregateTable, t, pool, &tree_[l], &file_[l]));
    }
    return Status::Ok();
  }
  BTree* level(int l) { return tree_[l].get(); }

 private:
  Database& db_;
  std::vector<std::unique_ptr<BTree>> tree_;
  std::vector<std::string> file_;
};

// The levels' records merged in key order (a level's octants come in
// Morton order; an ancestor sorts just before its descendants) into table,
// committed.
Status merge_levels(LevelFiles& levels, int count, BTree* table, uint64_t* records) {
  std::vector<BTreeCursor> at(static_cast<size_t>(count));
  for (int l = 0; l < count; ++l) {
    WEAVER_RETURN_IF_ERROR(levels.level(l)->commit());
    WEAVER_RETURN_IF_ERROR(levels.level(l)->seek_cursor(0, &at[l]));
  }
  for (;;) {
    int least = -1;  // a handful of levels: a scan beats a heap
    for (int l = 0; l < count; ++l) {
      if (at[l].valid() && (least < 0 || at[l].key() < at[least].key())) least = l;
    }
    if (least < 0) break;
    WEAVER_RETURN_IF_ERROR(table->append(at[least].key(), at[least].payload()));
    ++*records;
    WEAVER_RETURN_IF_ERROR(at[least].next());
  }
  return table->commit();
}

// The leaves per level of an octant table: from its metadata, or counted.
LevelCounts leaf_levels(BTree& octants) {
  LevelCounts n{};
  if (!levels_from_metadata(octants.options().metadata, &n)) n[kMaxLevel] = octants.size();
  return n;
}

}  // namespace

void SummaryBuilder::reset() {
  leaves_ = 0;
  level_min_ = kMaxLevel, level_max_ = 0;
  sum_.fill(0);
  volume_ = 0;
  min_.fill(INFINITY);
  max_.fill(-INFINITY);
}

void SummaryBuilder::add_leaf(int level, const float* values, int fields) {
  const double volume = double(uint64_t{1} << (3 * (kMaxLevel - level)));  // cubic ticks
  ++leaves_;
  level_min_ = std::min(level_min_, level);
  level_max_ = std::max(level_max_, level);
  for (int f = 0; f < fields; ++f) {
    min_[f] = std::min(min_[f], values[f]);
    max_[f] = std::max(max_[f], values[f]);
    sum_[f] += double(values[f]) * volume;
  }
  volume_ += volume;
}

void SummaryBuilder::add(const SummaryBuilder& o, int fields) {
  leaves_ += o.leaves_;
  level_min_ = std::min(level_min_, o.level_min_);
  level_max_ = std::max(level_max_, o.level_max_);
  for (int f = 0; f < fields; ++f) {
    min_[f] = std::min(min_[f], o.min_[f]);
    max_[f] = std::max(max_[f], o.max_[f]);
    sum_[f] += o.sum_[f];
  }
  volume_ += o.volume_;
}

Aggregate SummaryBuilder::result(int fields) const {
  Aggregate a;
  a.leaves = leaves_, a.level_min = level_min_, a.level_max = level_max_;
  for (int f = 0; f < fields; ++f) {
    a.min[f] = min_[f], a.max[f] = max_[f], a.mean[f] = float(sum_[f] / volume_);
  }
  return a;
}

LeafFields::LeafFields(BTree& octants) {
  const RecordSchema& schema = octants.options().schema;
  int n = 0;
  while (n < 5 && schema.find(kAggregateFields[n]) != nullptr) ++n;
  count_ = n >= 5 ? 5 : n >= 3 ? 3 : 0;
  for (int f = 0; f < count_; ++f) field_[f] = schema.find(kAggregateFields[f]);
}

void LeafFields::read(const std::byte* payload, float* out) const {
  for (int f = 0; f < count_; ++f) out[f] = float(RecordSchema::get_double(payload, *field_[f]));
}

AggregateLayout::AggregateLayout(bool material, bool q) : fields_(q ? 5 : material ? 3 : 0) {}

std::string AggregateLayout::schema_text() const {
  std::string s = "leaves:u64,level_min:u8,level_max:u8";
  for (int f = 0; f < fields_; ++f) {
    const std::string n = kAggregateFields[f];
    s += "," + n + "_min:f32," + n + "_max:f32," + n + "_mean:f32";
  }
  return s;
}

Status AggregateLayout::of_table(BTree& table, AggregateLayout* out) {
  const std::string text = table.options().schema.to_text();
  for (const AggregateLayout l :
       {AggregateLayout(false, false), AggregateLayout(true, false), AggregateLayout(true, true)}) {
    if (l.schema_text() == text) return *out = l, Status::Ok();
  }
  return Status::Corruption(table.file_name() + ": not an aggregate table's schema: " + text);
}

void AggregateLayout::encode(const Aggregate& a, std::byte* out) const {
  std::memcpy(out, &a.leaves, 8);
  out[8] = std::byte(a.level_min), out[9] = std::byte(a.level_max);
  for (int f = 0; f < fields_; ++f) {
    std::memcpy(out + 10 + 12 * f, &a.min[f], 4);
    std::memcpy(out + 14 + 12 * f, &a.max[f], 4);
    std::memcpy(out + 18 + 12 * f, &a.mean[f], 4);
  }
}

void AggregateLayout::decode(const std::byte* in, Aggregate* a) const {
  *a = Aggregate{};
  std::memcpy(&a->leaves, in, 8);
  a->level_min = int(in[8]), a->level_max = int(in[9]);
  for (int f = 0; f < fields_; ++f) {
    std::memcpy(&a->min[f], in + 10 + 12 * f, 4);
    std::memcpy(&a->max[f], in + 14 + 12 * f, 4);
    std::memcpy(&a->mean[f], in + 18 + 12 * f, 4);
  }
}

int aggregate_finest(BTree& table) {
  const std::string v = metadata_value(table.options().metadata, "finest");
  return v.empty() ? -1 : std::atoi(v.c_str());
}

Status build_aggregates(const std::string& db_dir, const AggregateOptions& o,
                        AggregateReport* report) {
  *report = AggregateReport{};
  // The writer's lock first, so that the octants read are the ones the
  // table is committed beside.
  std::unique_ptr<Database> db;
  WEAVER_RETURN_IF_ERROR(Database::open(db_dir, Database::Mode::kWrite, false, &db));
  MemoryPlan plan(o.memory);
  const uint64_t pool = plan.take("octant table pool", 1, 4);
  const uint64_t level_pools = plan.take("the levels' table files", 1, 2);
  const uint64_t write_pool = plan.take("aggregate table pool", 1, 8);
  if (!db->has_table(kOctantTable)) {
    return Status::InvalidArgument(db_dir + " has no octant table to summarise");
  }
  std::unique_ptr<Mesh> mesh;
  WEAVER_RETURN_IF_ERROR(Mesh::open(db_dir, pool, 1 << 20, &mesh, true));
  BTree& octants = mesh->octants();
  const int fields = LeafFields(octants).count();
  const AggregateLayout layout(fields >= 3, fields == 5);
  // The levels that fit a table of at most a 64th as many records as
  // leaves (4M for small meshes): the coarse levels, whose octants hold too
  // many leaves to summarise on the fly.
  const LevelCounts leaves = leaf_levels(octants);
  const uint64_t max_records =
      o.max_records ? o.max_records : std::max<uint64_t>(octants.size() / 64, 4 << 20);
  const int finest =
      std::min({kMaxLevel - 1, finest_level(leaves) - 1, finest_that_fits(leaves, max_records)});
  TableOptions t;
  t.key_kind = KeyKind::kOctant;
  t.packed = true;
  std::string error;
  t.schema = *RecordSchema::parse(layout.schema_text(), &error);
  LevelFiles levels(*db);
  WEAVER_RETURN_IF_ERROR(levels.create(finest + 1, t, level_pools / (finest + 2)));
  std::vector<std::byte> payload(layout.record_size());
  Summarizer s(finest, fields, [&](int level, const Open& open) {
    layout.encode(open.sum.result(fields), payload.data());
    return levels.level(level)->append(open.key, payload.data());
  });
  WEAVER_RETURN_IF_ERROR(scan_octants(octants, s, o.progress));
  report->leaves = octants.size();
  report->finest = -1;
  for (int l = 0; l <= finest; ++l) {
    if (levels.level(l)->size() > 0) report->finest = l;
  }
  t.metadata = "finest=" + std::to_string(report->finest);
  std::unique_ptr<BTree> table;
  std::string file;
  WEAVER_RETURN_IF_ERROR(db->create_table(kAggregateTable, t, write_pool, &table, &file));
  const Status st = merge_levels(levels, finest + 1, table.get(), &report->records);
  report->bytes = st.ok() ? table->file_bytes() : 0;
  return db->publish(kAggregateTable, file, table, st);
}

Status check_aggregates(BTree& octants, BTree& table, size_t max_problems,
                        std::vector<std::string>* problems) {
  AggregateLayout layout(false, false);
  WEAVER_RETURN_IF_ERROR(AggregateLayout::of_table(table, &layout));
  const int fields = LeafFields(octants).count();
  if (layout.fields() != fields) {
    problems->push_back("table aggregates: summarises " + std::to_string(layout.fields()) +
                        " fields, the octant table has " + std::to_string(fields));
    return Status::Ok();
  }
  LeafWindow window(table, true);
  uint64_t matched = 0;
  const auto problem = [&](const std::string& text) {
    if (problems->size() < max_problems) problems->push_back("table aggregates: " + text);
  };
  std::vector<std::byte> expect(layout.record_size());
  Summarizer s(aggregate_finest(table), fields, [&](int, const Open& open) {
    const std::byte* stored = nullptr;
    bool found = false;
    WEAVER_RETURN_IF_ERROR(window.get(open.key, &stored, &found));
    const auto where = [&open] { return describe_octant(octant_from_key(open.key)); };
    if (!found) return problem("no record for octant " + where()), Status::Ok();
    layout.encode(open.sum.result(fields), expect.data());
    if (std::memcmp(stored, expect.data(), expect.size()) != 0) {
      problem("the record of octant " + where() + " differs from its leaves' summary");
    }
    ++matched;
    return Status::Ok();
  });
  WEAVER_RETURN_IF_ERROR(scan_octants(octants, s, nullptr));
  if (matched != table.size() && problems->empty()) {
    problem(std::to_string(table.size()) + " records, " + std::to_string(matched) +
            " octants hold leaves");
  }
  return Status::Ok();
}

}  // namespace weaver
