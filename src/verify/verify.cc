#include "verify/verify.h"

#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cstring>
#include <filesystem>
#include <memory>
#include <vector>

#include "balance/balance.h"
#include "boundary/boundary.h"
#include "db/aggregate_table.h"
#include "db/boundary_table.h"
#include "db/database.h"
#include "db/leaf_reader.h"
#include "db/node_table.h"
#include "db/octant_table.h"
#include "extract/extract.h"
#include "model/ground_model.h"
#include "modeldb/import_source.h"
#include "modeldb/model_table.h"
#include "query/aggregates.h"
#include "storage/btree.h"
#include "util/leaf_span.h"
#include "util/ordered_run.h"
#include "util/parallel.h"
#include "verify/mesh_check.h"

namespace weaver {
namespace {

std::string count_text(uint64_t n, const char* what) { return std::to_string(n) + " " + what; }

// The levels of keys into counted, and what they span into *span: four
// counts a level, taken in turn (one count a level waited on its last
// increment for every key), and their box and volume.
void count_and_span(const std::vector<uint64_t>& keys, LevelCounts* counted, LeafSpan* span) {
  std::array<LevelCounts, 4> counts{};
  const size_t n = keys.size();
  size_t i = 0;
  for (; i + 4 <= n; i += 4) {
    for (int k = 0; k < 4; ++k) ++counts[k][octant_key_level(keys[i + k])];
  }
  for (; i < n; ++i) ++counts[0][octant_key_level(keys[i])];
  for (const LevelCounts& c : counts) {
    for (int l = 0; l <= kMaxLevel; ++l) (*counted)[l] += c[l];
  }
  if (span == nullptr) return;
  for (uint64_t k : keys) span->add(octant_from_key(k));
}

// Octant keys: valid, non-overlapping (LeafReader), and counted per level as
// the metadata says; what they span into *span (null: not asked), settled (the boundary's
// check needs it, and would read the table again to find it).
Status scan_octants(BTree& t, const std::string& name, Problems& problems, LeafSpan* span) {
  LeafReader reader;
  LevelCounts counted{};
  if (span != nullptr) *span = LeafSpan{};
  Status st = reader.open(t);
  // A leaf page's keys at a time, checked without a branch each (take), not
  // a call and a Status a key.
  std::vector<uint64_t> keys;
  while (st.ok() && reader.valid()) {
    keys.clear();
    st = reader.take(4096, UINT64_MAX, &keys);
    count_and_span(keys, &counted, span);
  }
  if (span != nullptr) span->settle();
  if (!st.ok()) {
    if (st.code() == Status::Code::kIOError) return st;
    problems.add("table " + name + ": " + st.message());
    return Status::Ok();
  }
  LevelCounts stored{};
  if (levels_from_metadata(t.options().metadata, &stored) && stored != counted) {
    for (int l = 0; l <= kMaxLevel; ++l) {
      if (stored[l] == counted[l]) continue;
      problems.add("table " + name + ": metadata counts " + std::to_string(stored[l]) +
                   " leaves at level " + std::to_string(l) + ", the table holds " +
                   std::to_string(counted[l]));
      break;
    }
  }
  return Status::Ok();
}

// A model table's values: in range, as import leaves them (velocities and
// density positive, Q not negative, all finite).
Status scan_model(BTree& t, const std::string& name, Problems& problems) {
  const int fields =
      static_cast<int>(std::min<size_t>(t.options().schema.record_size() / 4, kModelFields));
  BTreeCursor c;
  WEAVER_RETURN_IF_ERROR(t.seek_cursor(0, &c));
  while (c.valid()) {
    ModelValues v{};
    std::memcpy(v.data(), c.payload(), 4 * size_t(fields));
    if (const int bad = bad_model_field(v, fields); bad >= 0) {
      problems.add(
          bad_model_value("table " + name + ": octant " + describe_octant(octant_from_key(c.key())),
                          v, bad)
              .message());
      return Status::Ok();
    }
    WEAVER_RETURN_IF_ERROR(c.next());
  }
  return Status::Ok();
}

// Node keys and kinds: a leaf page's records at a time, checked without a
// branch each and from the key (node_key_is_valid), not decoded: a call, a
// decode and a branch a node took a fifth of a 1 Hz verify.
Status scan_nodes(BTree& t, const std::string& name, Problems& problems) {
  const size_t stride = t.options().schema.record_size();
  BTreeCursor c;
  WEAVER_RETURN_IF_ERROR(t.seek_cursor(0, &c));
  for (uint64_t id = 0; c.valid();) {
    uint32_t n = 0;
    const uint64_t* keys = c.keys_in_leaf(&n);
    const std::byte* kinds = c.payload();  // the leaf's records' in a row
    bool good = true;
    for (uint32_t i = 0; i < n; ++i) {
      good &= node_key_is_valid(keys[i]) & (static_cast<uint8_t>(kinds[i * stride]) <= 2);
    }
    for (uint32_t i = 0; !good && i < n; ++i) {
      if (node_key_is_valid(keys[i]) && static_cast<uint8_t>(kinds[i * stride]) <= 2) continue;
      problems.add("table " + name + ": node " + std::to_string(id + i) + " (key " +
                   std::to_string(keys[i]) + ") has an invalid coordinate or kind");
      return Status::Ok();
    }
    id += n;
    WEAVER_RETURN_IF_ERROR(c.skip(n));
  }
  return Status::Ok();
}

// Pages and keys of one table.  *usable is false when the table is too
// damaged for the mesh checks; *line is its progress line.
Status check_table(const Database& db, const std::string& name, uint64_t pool_bytes,
                   Problems& problems, VerifyReport* r, bool* usable, std::string* line,
                   LeafSpan* span) {
  *usable = false;
  std::unique_ptr<BTree> t;
  Status st = db.open_table(name, pool_bytes, &t);
  if (st.ok()) st = t->check_invariants();
  if (!st.ok()) {
    problems.add("table " + name + ": " + st.message());
    return Status::Ok();
  }
  ++r->tables;
  r->records += t->size();
  r->pages += t->page_count();
  const size_t before = r->problems.size();
  if (name == kAggregateTable) {
    // Nested octants, not leaves: checked against the octant table below.
  } else if (t->options().key_kind == KeyKind::kOctant) {
    // The span for the octant table alone: the boundary's check reads it.
    WEAVER_RETURN_IF_ERROR(scan_octants(*t, name, problems, name == kOctantTable ? span : nullptr));
    if (name == kModelTable) WEAVER_RETURN_IF_ERROR(scan_model(*t, name, problems));
  } else if (name == kNodeTable) {
    WEAVER_RETURN_IF_ERROR(scan_nodes(*t, name, problems));
  }
  *usable = r->problems.size() == before;
  *line = "table " + name + ": " + count_text(t->size(), "records") + ", " +
          count_text(t->page_count(), "pages") + (*usable ? ": ok" : ": PROBLEMS");
  return Status::Ok();
}

// One table's storage check, made apart from the others'.
struct TableCheck {
  size_t table = 0;     // its index in the names
  VerifyReport report;  // its counts and problems
  std::string line;     // its progress line
  LeafSpan span;        // the octant table's leaves' (scan_octants)
  bool usable = false;
  Status status;
};

// Every table's storage check, on up to o.threads threads (a table each at
// a time, the pool's share cut between them: one read the tables of the
// 1 Hz mesh in 3.4 s, a third of verify), reported in table order as one
// thread would (util/ordered_run.h): the same problems, lines and counts on
// any count.  A table whose check failed (an I/O error) ends the report, as
// it ended one thread's loop.  *usable[i]: whether table i can serve the
// mesh checks; *octant_span: what the octant table's leaves span.
Status check_tables(const Database& db, const std::vector<std::string>& names, uint64_t pool_bytes,
                    const VerifyOptions& o, Problems& problems, VerifyReport* r,
                    std::vector<bool>* usable, LeafSpan* octant_span) {
  const int threads = std::max(1, std::min(o.threads, static_cast<int>(names.size())));
  usable->assign(names.size(), false);
  size_t next = 0;
  Status st;
  auto make = [&](TableCheck* c) {
    if (next == names.size()) return false;
    *c = TableCheck{};
    c->table = next++;
    return true;
  };
  auto work = [&](int, TableCheck* c) {
    Problems found(o, &c->report);  // (check_table hands its line back, never prints it)
    c->status = check_table(db, names[c->table], pool_bytes / threads, found, &c->report,
                            &c->usable, &c->line, &c->span);
  };
  auto write = [&](TableCheck* c) {
    st = c->status;
    if (!st.ok()) return false;
    for (std::string& p : c->report.problems) problems.add(std::move(p));
    r->tables += c->report.tables;
    r->records += c->report.records;
    r->pages += c->report.pages;
    (*usable)[c->table] = c->usable;
    if (names[c->table] == kOctantTable) *octant_span = c->span;
    if (!c->line.empty()) problems.progress(c->line);
    return true;
  };
  // Every table may be in flight at once (a few): a large one then holds up
  // only the report, not the checks of those after it.
  OrderedRun<TableCheck>(std::max<size_t>(names.size(), 1), make, work, write).go(threads);
  return st;
}

// One thread's share of the node check: table handles of its own (a B+tree
// serves one thread), its counts and its problems.
struct NodeShare {
  std::unique_ptr<BTree> octants, nodes;
  VerifyReport report;
};

// The independent node check (--independent): every node classified again
// from the leaves around it, its id range cut into one share a thread.  The
// shares' problems are kept in share order, so the first ones named are
// those of the lowest node ids, whatever the thread count.
Status check_nodes_each(const Database& db, const VerifyMemory& memory, const VerifyOptions& o,
                        Problems& problems, VerifyReport* r) {
  const int n = std::max(1, o.threads);
  std::vector<NodeShare> shares(static_cast<size_t>(n));
  for (NodeShare& s : shares) {
    WEAVER_RETURN_IF_ERROR(db.open_table(kOctantTable, memory.octant_pool / n, &s.octants));
    WEAVER_RETURN_IF_ERROR(db.open_table(kNodeTable, memory.node_pool / n, &s.nodes));
  }
  const uint64_t total = shares[0].nodes->size();
  if (o.nodes_progress) o.nodes_progress(0, 0.0);  // the node check starts
  std::atomic<uint64_t> checked{0};
  WEAVER_RETURN_IF_ERROR(run_shares(n, [&](int i) {
    NodeShare& s = shares[static_cast<size_t>(i)];
    Problems mine(o, &s.report);
    const auto count = [&](uint64_t k) {
      const uint64_t now = checked.fetch_add(k) + k;
      if (i == 0 && o.nodes_progress) o.nodes_progress(now, double(now) / double(total));
    };
    return check_node_range(*s.octants, *s.nodes, total * i / n, total * (i + 1) / n, count, mine,
                            &s.report);
  }));
  for (NodeShare& s : shares) {
    for (std::string& p : s.report.problems) problems.add(std::move(p));
    r->nodes += s.report.nodes;
    r->dangling += s.report.dangling;
    r->corners += s.report.corners;
  }
  return check_corner_total(*shares[0].octants, *shares[0].nodes, problems, r);
}

// The node check: the nodes derived again by the extraction's own bucket
// sort (o.threads workers), compared with the stored table in key order
// (NodeStreamCheck).  Its spills go to the system's temporary directory:
// verify writes nothing into the database.
Status check_nodes(const Database& db, const VerifyMemory& memory, const VerifyOptions& o,
                   Problems& problems, VerifyReport* r, bool* balanced) {
  std::unique_ptr<BTree> octants, nodes;
  WEAVER_RETURN_IF_ERROR(db.open_table(kOctantTable, memory.octant_pool, &octants));
  WEAVER_RETURN_IF_ERROR(db.open_table(kNodeTable, memory.node_pool, &nodes));
  NodeStreamCheck check(*octants, *nodes, problems, r);
  WEAVER_RETURN_IF_ERROR(check.open());
  ExtractOptions x;
  x.memory = memory.derive;
  x.threads = std::max(1, o.threads);
  if (o.nodes_progress) o.nodes_progress(0, 0.0);  // the node check starts
  const double total = std::max<double>(1, double(nodes->size()));
  const std::string scratch =
      (std::filesystem::temp_directory_path() / ("weaver-verify-" + std::to_string(::getpid())))
          .string();
  ExtractResult er;
  const Status st = derive_nodes(
      db, x, scratch,
      [&](const uint64_t* keys, const std::byte* kinds, size_t n) {
        WEAVER_RETURN_IF_ERROR(check.compare(keys, kinds, n));
        // Nodes compared, of the table (called from one thread).
        if (o.nodes_progress) o.nodes_progress(r->nodes, double(r->nodes) / total);
        return Status::Ok();
      },
      &er);
  // The derivation refuses what cannot be a mesh: leaves more than a level
  // apart across a face or edge, or overlapping.
  *balanced = st.code() != Status::Code::kInvalidArgument;
  if (st.code() == Status::Code::kInvalidArgument) {
    problems.add("mesh: not 2:1 balanced: " + st.message());
    return Status::Ok();
  }
  if (st.code() == Status::Code::kCorruption)
    return problems.add("mesh: " + st.message()), Status::Ok();
  WEAVER_RETURN_IF_ERROR(st);
  return check.finish(octants->size());
}

// The aggregate table against a summary of the octant table made again.
Status check_aggregate_table(const Database& db, const VerifyMemory& memory, Problems& problems) {
  std::unique_ptr<BTree> octants, aggregates;
  WEAVER_RETURN_IF_ERROR(db.open_table(kOctantTable, memory.octant_pool, &octants));
  WEAVER_RETURN_IF_ERROR(db.open_table(kAggregateTable, memory.table_pool, &aggregates));
  std::vector<std::string> found;
  const Status st = check_aggregates(*octants, *aggregates, 20, &found);
  if (!st.ok()) {
    if (st.code() == Status::Code::kIOError) return st;
    found.push_back("table aggregates: " + st.message());
  }
  for (std::string& p : found) problems.add(std::move(p));
  problems.progress(std::string("table aggregates: summaries of the leaves: ") +
                    (found.empty() ? "ok" : "PROBLEMS"));
  return Status::Ok();
}

// The boundary table against the records derived again from the octants,
// on o.threads threads (a handle of the octant table each; the later ones
// hold their records, 16 bytes each and room for a vector's growth, in the
// node check's share, not yet in use).  span: the octant table's leaves',
// as its storage check found it.
Status check_boundary_table(const Database& db, const VerifyMemory& memory, const VerifyOptions& o,
                            const LeafSpan& span, Problems& problems) {
  const int threads = std::max(1, o.threads);
  std::vector<std::unique_ptr<BTree>> handles(static_cast<size_t>(threads));
  std::vector<BTree*> octants;
  for (auto& h : handles) {
    WEAVER_RETURN_IF_ERROR(db.open_table(kOctantTable, memory.octant_pool / threads, &h));
    octants.push_back(h.get());
  }
  std::unique_ptr<BTree> stored;
  WEAVER_RETURN_IF_ERROR(db.open_table(kBoundaryTable, memory.node_pool, &stored));
  const uint64_t held =
      threads > 1 ? std::max<uint64_t>(1, memory.derive.bytes() / 32 / uint64_t(threads - 1)) : 0;
  std::vector<std::string> found;
  WEAVER_RETURN_IF_ERROR(
      check_boundary(octants, *stored, MemoryBudget(memory.surface), held, 20, &span, &found));
  for (std::string& p : found) problems.add(std::move(p));
  problems.progress(std::string("table boundary: the faces derived again: ") +
                    (found.empty() ? "ok" : "PROBLEMS"));
  return Status::Ok();
}

Status check_mesh(const Database& db, const VerifyMemory& memory, const VerifyOptions& o,
                  Problems& problems, VerifyReport* r) {
  if (!o.independent) {
    // The derivation checks the balance as it goes (a node inside a leaf's
    // face or edge away from its midpoint: a neighbour two levels finer).
    r->mesh_checked = true;
    const size_t before = r->problems.size();
    bool balanced = true;
    WEAVER_RETURN_IF_ERROR(check_nodes(db, memory, o, problems, r, &balanced));
    problems.progress(std::string("mesh: 2:1 balance: ") + (balanced ? "ok" : "VIOLATED"));
    if (!balanced) return Status::Ok();
    problems.progress("mesh: " + count_text(r->nodes, "nodes") + " (" +
                      count_text(r->dangling, "dangling") + "), " +
                      count_text(r->corners, "element corners") +
                      (r->problems.size() == before ? ": ok" : ": PROBLEMS"));
    return Status::Ok();
  }
  BalanceResult br;
  {
    std::unique_ptr<BTree> octants;  // closed before the node check opens its own
    WEAVER_RETURN_IF_ERROR(db.open_table(kOctantTable, memory.octant_pool, &octants));
    BalanceOptions bo;
    bo.memory = memory.balance_check;
    bo.check_only = true;
    bo.threads = o.threads;
    WEAVER_RETURN_IF_ERROR(
        check_balance(*octants, bo, std::filesystem::temp_directory_path().string(), &br));
  }
  if (!br.balanced) problems.add("mesh: not 2:1 balanced: " + br.violation);
  problems.progress(std::string("mesh: 2:1 balance: ") + (br.balanced ? "ok" : "VIOLATED"));
  if (problems.full()) return Status::Ok();
  r->mesh_checked = true;
  const size_t before = r->problems.size();
  WEAVER_RETURN_IF_ERROR(check_nodes_each(db, memory, o, problems, r));
  problems.progress("mesh: " + count_text(r->nodes, "nodes") + " (" +
                    count_text(r->dangling, "dangling") + "), " +
                    count_text(r->corners, "element corners") +
                    (r->problems.size() == before ? ": ok" : ": PROBLEMS"));
  return Status::Ok();
}

}  // namespace

VerifyMemory::VerifyMemory(MemoryBudget budget) : plan(budget) {
  // The storage check reads its tables in page order, one a thread at a
  // time, this share cut between them.
  table_pool = plan.take("table pool (storage check)", 1, 8);
  // The mesh check reads the nodes in order, looks up the anchors of the
  // dangling ones, and looks for the leaves around a node that differs.
  octant_pool = plan.take("octant table pool", 1, 8);
  node_pool = plan.take("node table pool", 1, 8);
  // The balance check sorts the leaves' requirements out of core; after
  // it, the same share derives the nodes again (as weaver extract would).
  balance_check = plan.take_budget("balance check, then the nodes derived again", 1, 2);
  derive = balance_check;
  surface = table_pool;
}

// A mesh under a ground surface: every solid fraction in (0, 1], and no
// element wholly above the ground (the surface read again as the metadata
// names it; a surface that cannot be read is a problem too).
Status check_ground(Database& db, const VerifyMemory& memory, Problems& problems) {
  std::unique_ptr<BTree> t;
  WEAVER_RETURN_IF_ERROR(db.open_table(kOctantTable, memory.octant_pool, &t));
  const Field* solid = t->options().schema.find("solid");
  if (solid == nullptr) return Status::Ok();
  std::unique_ptr<Surface> surface;
  Ground ground;
  const Status loaded =
      ground_of_metadata(t->options().metadata, memory.surface, &surface, &ground);
  if (!loaded.ok())
    problems.add("table octants: its ground cannot be read again: " + loaded.message());
  Units units;
  units_from_metadata(t->options().metadata, &units);
  BTreeCursor c;
  WEAVER_RETURN_IF_ERROR(t->seek_cursor(0, &c));
  for (uint64_t id = 0; c.valid() && !problems.full(); ++id) {
    const double f = RecordSchema::get_double(c.payload(), *solid);
    const Octant o = octant_from_key(c.key());
    if (!(f > 0 && f <= 1)) {
      problems.add("element " + std::to_string(id) + " (" + describe_octant(o) +
                   "): solid fraction " + std::to_string(f) + ", not in (0, 1]");
    } else if (loaded.ok()) {
      const double e = octant_edge(o) * units.tick_m;
      const double lo[3] = {o.x * units.tick_m, o.y * units.tick_m, o.z * units.tick_m};
      const double hi[3] = {lo[0] + e, lo[1] + e, lo[2] + e};
      if (side_of_ground(ground, lo, hi) == GroundSide::kAir) {
        problems.add("element " + std::to_string(id) + " (" + describe_octant(o) +
                     ") lies wholly above the ground");
      }
    }
    WEAVER_RETURN_IF_ERROR(c.next());
  }
  problems.progress("ground: solid fractions and the surface: checked");
  return Status::Ok();
}

Status verify_database(const std::string& dir, const VerifyOptions& o, VerifyReport* r) {
  *r = VerifyReport{};
  Problems problems(o, r);
  std::unique_ptr<Database> db;
  Status st = Database::open(dir, Database::Mode::kRead, false, &db);
  if (!st.ok()) {
    if (st.code() == Status::Code::kCorruption) return problems.add(st.message()), Status::Ok();
    return st;
  }
  const VerifyMemory memory(o.memory);
  bool mesh_usable = o.mesh && db->has_table(kOctantTable) && db->has_table(kNodeTable);
  bool octants_usable = db->has_table(kOctantTable);
  const std::vector<std::string> names = db->table_names();
  std::vector<bool> usable;
  LeafSpan octant_span;
  WEAVER_RETURN_IF_ERROR(
      check_tables(*db, names, memory.table_pool, o, problems, r, &usable, &octant_span));
  for (size_t i = 0; i < names.size(); ++i) {
    if (!usable[i] && (names[i] == kOctantTable || names[i] == kNodeTable)) mesh_usable = false;
    if (!usable[i] && names[i] == kOctantTable) octants_usable = false;
  }
  if (octants_usable && db->has_table(kAggregateTable) && !problems.full()) {
    WEAVER_RETURN_IF_ERROR(check_aggregate_table(*db, memory, problems));
  }
  if (octants_usable && o.mesh && !problems.full()) {
    WEAVER_RETURN_IF_ERROR(check_ground(*db, memory, problems));
  }
  if (octants_usable && o.mesh && db->has_table(kBoundaryTable) && !problems.full()) {
    WEAVER_RETURN_IF_ERROR(check_boundary_table(*db, memory, o, octant_span, problems));
  }
  if (mesh_usable) WEAVER_RETURN_IF_ERROR(check_mesh(*db, memory, o, problems, r));
  return Status::Ok();
}

}  // namespace weaver
