#include "boundary/boundary.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "boundary/boundary_scan.h"
#include "db/boundary_table.h"
#include "db/octant_table.h"
#include "util/parallel.h"

namespace weaver {
namespace {

namespace scan = boundary_scan;

// Adds a later range's result to *r (ranges in id order: the first least
// edge / vp kept on a tie, as one scan finds it).
void add_result(const BoundaryResult& later, BoundaryResult* r) {
  r->elements += later.elements, r->faces += later.faces, r->quarters += later.quarters;
  r->free_surface += later.free_surface, r->asked += later.asked;
  if (later.elements > 0 && later.least_dt > 0 &&
      (r->least_dt == 0 || later.least_dt < r->least_dt))
    r->least_dt = later.least_dt, r->least_dt_element = later.least_dt_element;
}

// The boundary records of the whole octant table, into `out` in key order,
// on one thread a handle of the table (tables[0] the caller's): the ids cut
// into equal ranges, range 0 derived straight into `out`, the others at the
// same time into memory, up to cap records each, then handed on in turn
// (the rest of a range whose worker stopped at its cap derived then).
Status derive_boundary(const std::vector<BTree*>& tables, const scan::BoundarySink& out,
                       const BoundaryOptions& o, MemoryBudget surface, uint64_t cap,
                       BoundaryResult* r) {
  BTree& octants = *tables[0];
  const int t = int(tables.size());
  const uint64_t n = octants.size();
  const auto cut = [&](int i) { return n * uint64_t(i) / uint64_t(t); };
  scan::Span span;
  if (o.known_box) {
    span.lo = o.box_lo, span.hi = o.box_hi, span.filled = o.box_filled;
  } else {
    std::vector<scan::Share> shares(tables.size());
    WEAVER_RETURN_IF_ERROR(run_shares(t, [&](int i) {
      return scan::share_of(*tables[i], cut(i), cut(i + 1), nullptr, &shares[i]);
    }));
    for (const scan::Share& s : shares) span.add(s.span);
    span.settle();
  }
  scan::GroundCheck ground;  // read-only once loaded: the threads share it
  scan::load_ground(octants, span, surface, &ground);
  const Field* vp = o.known_least_dt > 0 ? nullptr : octants.options().schema.find("vp");
  scan::Tally tally;
  tally.total = n, tally.report = o.progress;
  struct Range {
    std::vector<std::pair<uint64_t, uint8_t>> records;
    uint64_t reached = 0;
    BoundaryResult r;
  };
  std::vector<Range> ranges(tables.size());
  WEAVER_RETURN_IF_ERROR(run_shares(t, [&](int i) {
    Range& g = ranges[size_t(i)];
    if (i == 0) {
      return scan::derive_records(octants, out, span, ground, 0, cut(1), vp, &tally, true, nullptr,
                                  &g.reached, &g.r);
    }
    const scan::BoundarySink keep = [&g](uint64_t key, uint8_t kind) {
      g.records.emplace_back(key, kind);
      return Status::Ok();
    };
    return scan::derive_records(
        *tables[size_t(i)], keep, span, ground, cut(i), cut(i + 1), vp, &tally, false,
        [&g, cap] { return g.records.size() >= cap; }, &g.reached, &g.r);
  }));
  *r = ranges[0].r;
  for (int i = 1; i < t; ++i) {
    Range& g = ranges[size_t(i)];
    for (const auto& [key, kind] : g.records) WEAVER_RETURN_IF_ERROR(out(key, kind));
    add_result(g.r, r);
    std::vector<std::pair<uint64_t, uint8_t>>().swap(g.records);
    if (g.reached < cut(i + 1)) {  // stopped at its cap: the rest here
      BoundaryResult rest;
      uint64_t reached = 0;
      WEAVER_RETURN_IF_ERROR(scan::derive_records(octants, out, span, ground, g.reached, cut(i + 1),
                                                  vp, &tally, true, nullptr, &reached, &rest));
      add_result(rest, r);
    }
  }
  r->filled = span.filled;
  if (o.known_least_dt > 0)
    r->least_dt = o.known_least_dt, r->least_dt_element = o.known_least_dt_element;
  return Status::Ok();
}

Status write_boundary(const std::vector<BTree*>& octants, BTree& out, const BoundaryOptions& o,
                      MemoryBudget surface, uint64_t cap, BoundaryResult* r) {
  const scan::BoundarySink append = [&out](uint64_t key, uint8_t kind) {
    return out.append(key, reinterpret_cast<const std::byte*>(&kind));
  };
  WEAVER_RETURN_IF_ERROR(derive_boundary(octants, append, o, surface, cap, r));
  out.set_metadata(scan::boundary_metadata(*r));
  return Status::Ok();
}

}  // namespace

Status build_boundary(const std::string& db_dir, const BoundaryOptions& o, BoundaryResult* r) {
  *r = BoundaryResult{};
  MemoryPlan plan(o.memory);
  // Both scans and the lookups read the octant table (a handle a thread);
  // the writer appends.
  const int threads = std::max(1, o.threads);
  const uint64_t octant_pool = plan.take("octant table pools", 1, 4) / uint64_t(threads);
  const uint64_t out_pool = plan.take("boundary table pool", 1, 8, 8ull << 20);
  // A carved mesh's surface, read again (model/surface.h).
  const MemoryBudget surface = plan.take_budget("surface", 1, 4);
  // The records the threads past the first hold until their turn (twice
  // their bytes: room for a vector's growth).
  uint64_t cap = threads > 1 ? plan.take("records held by the other threads", 1, 4) /
                                   (2 * sizeof(std::pair<uint64_t, uint8_t>) * (threads - 1))
                             : 0;
  if (o.held_records > 0) cap = std::min(cap, o.held_records);
  std::unique_ptr<Database> own;
  Database* db = o.writer;
  if (db == nullptr) {
    WEAVER_RETURN_IF_ERROR(Database::open(db_dir, Database::Mode::kWrite, false, &own));
    db = own.get();
  }
  if (!db->has_table(kOctantTable)) return Status::NotFound(db_dir + ": no octant table");
  std::vector<std::unique_ptr<BTree>> handles(static_cast<size_t>(threads));
  std::vector<BTree*> octants;
  for (auto& h : handles) {
    WEAVER_RETURN_IF_ERROR(db->open_table(kOctantTable, octant_pool, &h));
    octants.push_back(h.get());
  }
  std::unique_ptr<BTree> table;
  std::string file;
  WEAVER_RETURN_IF_ERROR(db->create_table(kBoundaryTable, scan::boundary_table_options(o.packed),
                                          out_pool, &table, &file));
  const Status st = write_boundary(octants, *table, o, surface, cap, r);
  WEAVER_RETURN_IF_ERROR(db->publish(kBoundaryTable, file, table, st));
  r->table_bytes = table->file_bytes();
  return Status::Ok();
}

Status check_boundary(const std::vector<BTree*>& octants, BTree& stored, MemoryBudget surface,
                      uint64_t held, size_t max_problems, const LeafSpan* span,
                      std::vector<std::string>* problems) {
  std::unique_ptr<Cursor> c;
  WEAVER_RETURN_IF_ERROR(stored.seek(0, &c));
  auto where = [](uint64_t key) {
    return "element " + std::to_string(key >> 6) + " face " + std::to_string(key >> 3 & 7) +
           " part " + std::to_string(key & 7);
  };
  auto add = [&](std::string p) {
    if (problems->size() < max_problems) problems->push_back("table boundary: " + std::move(p));
  };
  // Both sides come in key order: walk them together.
  const scan::BoundarySink compare = [&](uint64_t key, uint8_t kind) -> Status {
    while (c->valid() && c->key() < key) {
      add(where(c->key()) + " is stored, but is not a boundary");
      WEAVER_RETURN_IF_ERROR(c->next());
    }
    if (!c->valid() || c->key() != key) {
      add(where(key) + " is a boundary, but is not stored");
      return Status::Ok();
    }
    const auto got = static_cast<uint8_t>(*c->payload());
    if (got != kind) {
      add(where(key) + " is stored as kind " + std::to_string(got) + ", not " +
          std::to_string(kind));
    }
    return c->next();
  };
  BoundaryOptions o;
  o.known_least_dt = 1;  // the time step is not the table's: keys alone
  if (span != nullptr) {
    o.known_box = true;
    o.box_lo = span->lo, o.box_hi = span->hi, o.box_filled = span->filled;
  }
  BoundaryResult r;
  WEAVER_RETURN_IF_ERROR(derive_boundary(octants, compare, o, surface, held, &r));
  while (c->valid()) {
    add(where(c->key()) + " is stored, but is not a boundary");
    WEAVER_RETURN_IF_ERROR(c->next());
  }
  return Status::Ok();
}

}  // namespace weaver
