// boundary_shard (boundary.h): a rank's share of the boundary table.
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "boundary/boundary.h"
#include "boundary/boundary_scan.h"
#include "db/boundary_table.h"
#include "db/table_files.h"

namespace weaver {

namespace scan = boundary_scan;

namespace {

// A rank's share as text for the others ("" when it failed), and back.
std::string share_text(const scan::Share& s) {
  char buf[320];
  std::snprintf(buf, sizeof buf, "%u %u %u %u %u %u %llu %llu %a %llu", s.span.lo[0], s.span.lo[1],
                s.span.lo[2], s.span.hi[0], s.span.hi[1], s.span.hi[2],
                (unsigned long long)(s.span.volume >> 64), (unsigned long long)s.span.volume,
                s.least_dt, (unsigned long long)s.least_dt_element);
  return buf;
}

bool parse_share(const std::string& text, scan::Share* s) {
  unsigned long long hi = 0, lo = 0, element = 0;
  char dt[64] = {};
  if (std::sscanf(text.c_str(), "%u %u %u %u %u %u %llu %llu %63s %llu", &s->span.lo[0],
                  &s->span.lo[1], &s->span.lo[2], &s->span.hi[0], &s->span.hi[1], &s->span.hi[2],
                  &hi, &lo, dt, &element) != 10) {
    return false;
  }
  s->span.volume = (static_cast<unsigned __int128>(hi) << 64) | lo;
  s->least_dt = std::strtod(dt, nullptr);
  s->least_dt_element = element;
  return true;
}

// Every rank's share, combined as one scan of the whole table finds them
// (the least edge / vp of the first rank that has it: the least id).
// False when a rank failed (sent "").
bool combine_shares(const std::vector<std::string>& texts, scan::Share* all) {
  *all = scan::Share{};
  for (const std::string& text : texts) {
    scan::Share s;
    if (!parse_share(text, &s)) return false;
    all->span.add(s.span);
    if (s.least_dt < all->least_dt)
      all->least_dt = s.least_dt, all->least_dt_element = s.least_dt_element;
  }
  all->span.settle();
  return true;
}

}  // namespace

Status boundary_shard(const std::string& db_dir, const BoundaryOptions& o, int rank, int ranks,
                      const std::string& file, const RankAllGather& all_gather, BoundaryResult* r,
                      ShardEntry* entry) {
  *r = BoundaryResult{};
  *entry = ShardEntry{file};
  MemoryPlan plan(o.memory);
  const uint64_t octant_pool = plan.take("octant table pool", 1, 4);
  const uint64_t out_pool = plan.take("boundary table pool", 1, 8, 8ull << 20);
  const MemoryBudget surface = plan.take_budget("surface", 1, 2);
  // Up to each exchange, an error still takes part in it (sending "").
  std::unique_ptr<Database> db;
  std::unique_ptr<BTree> octants;
  Status st = Database::open(db_dir, Database::Mode::kRead, false, &db);
  if (st.ok() && !o.staged_octants.empty()) {
    st = db->stage_shards(kOctantTable, o.staged_octants);
  }
  if (st.ok() && !db->has_table(kOctantTable)) st = Status::NotFound(db_dir + ": no octant table");
  if (st.ok()) st = db->open_table(kOctantTable, octant_pool, &octants);
  const uint64_t n = st.ok() ? octants->size() : 0;
  const uint64_t first = n * uint64_t(rank) / uint64_t(ranks);
  const uint64_t stop = n * uint64_t(rank + 1) / uint64_t(ranks);
  const Field* vp = st.ok() ? octants->options().schema.find("vp") : nullptr;
  scan::Share mine, all;
  if (st.ok()) st = scan::share_of(*octants, first, stop, vp, &mine);
  std::vector<std::string> texts;
  WEAVER_RETURN_IF_ERROR(all_gather(st.ok() ? share_text(mine) : "", &texts));
  WEAVER_RETURN_IF_ERROR(st);
  if (!combine_shares(texts, &all)) return Status::Ok();  // another rank failed: it says why
  // This rank's records, into a shard file of the table.
  std::unique_ptr<BTree> table;
  st = create_shard_table(db_dir, file, scan::boundary_table_options(o.packed), out_pool, &table);
  const scan::BoundarySink append = [&table](uint64_t key, uint8_t kind) {
    return table->append(key, reinterpret_cast<const std::byte*>(&kind));
  };
  if (st.ok()) {
    scan::GroundCheck ground;
    scan::load_ground(*octants, all.span, surface, &ground);
    scan::Tally tally;
    tally.total = stop - first, tally.report = o.progress;
    uint64_t reached = 0;
    st = scan::derive_records(*octants, append, all.span, ground, first, stop, nullptr, &tally,
                              true, nullptr, &reached, r);
  }
  // The counts of every rank, for the metadata every shard carries.
  char counts[96];
  std::snprintf(counts, sizeof counts, "%llu %llu", (unsigned long long)r->faces,
                (unsigned long long)r->free_surface);
  const Status gathered = all_gather(st.ok() ? counts : "", &texts);
  BoundaryResult total = *r;
  total.faces = total.free_surface = 0;
  std::vector<bool> writes;
  bool peer_failed = false;
  for (const std::string& text : texts) {
    unsigned long long faces = 0, free_surface = 0;
    if (std::sscanf(text.c_str(), "%llu %llu", &faces, &free_surface) != 2) {
      peer_failed = true;
      break;
    }
    total.faces += faces, total.free_surface += free_surface;
    writes.push_back(faces > 0);
  }
  if (st.ok()) st = gathered;
  total.least_dt = vp != nullptr && n > 0 ? all.least_dt : 0;
  total.least_dt_element = vp != nullptr ? all.least_dt_element : 0;
  r->least_dt = total.least_dt, r->least_dt_element = total.least_dt_element;
  if (table == nullptr) return st;
  // A failed rank says why; the others only drop their files.
  const bool drop = st.ok() && peer_failed;
  if (st.ok() && !drop) table->set_metadata(scan::boundary_metadata(total));
  const ShardPlace place = st.ok() && !drop ? shard_place_among(writes, rank) : ShardPlace{};
  const Status finished = finish_shard(db_dir, table, drop ? Status::Internal("dropped") : st,
                                       place, entry, &r->table_bytes);
  return drop ? Status::Ok() : finished;
}

}  // namespace weaver
