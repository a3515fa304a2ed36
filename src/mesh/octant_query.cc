#include "mesh/octant_query.h"

#include <string>

#include "db/octant_table.h"

namespace weaver {
namespace {

// Visits the leaves that meet a box in key order: counting them all, and
// handing those from id `from` on to on_leaf (at most `limit`) or, as runs
// of consecutive ids, to on_run.
struct RangeWalk {
  BTree& t;
  const TickBox& box;
  const std::function<void(const Octant&, uint64_t)>* on_leaf = nullptr;
  const std::function<Status(uint64_t, uint64_t)>* on_run = nullptr;
  uint64_t from = 0, limit = UINT64_MAX;
  uint64_t count = 0, listed = 0;
  uint64_t next = UINT64_MAX;           // the first leaf past a full page
  uint64_t run_first = 0, run_end = 0;  // the run not yet handed on

  bool wants_leaves() const { return on_leaf != nullptr || on_run != nullptr; }

  // Visits octant o, which intersects the box.
  Status visit(const Octant& o) {
    if (next != UINT64_MAX) return Status::Ok();  // the page is full
    const uint64_t key = octant_key(o);
    uint64_t floor_key = 0;
    bool found = false;
    WEAVER_RETURN_IF_ERROR(floor_holding(t, o, &floor_key, nullptr, &found));
    if (found) return emit_one(octant_from_key(floor_key), floor_key);
    uint64_t first = 0, end = 0;
    WEAVER_RETURN_IF_ERROR(t.rank(key, &first));
    WEAVER_RETURN_IF_ERROR(t.rank(octant_key_subtree_end(o), &end));
    if (end == first) return Status::Ok();                   // no leaves under o
    if (wants_leaves() && end <= from) return Status::Ok();  // before the page
    if (octant_in_box(o, box.lo, box.hi)) return emit_all(key, first, end);
    for (int k = 0; k < 8; ++k) {
      const Octant c = octant_child(o, k);
      if (octant_meets_box(c, box.lo, box.hi)) WEAVER_RETURN_IF_ERROR(visit(c));
    }
    return Status::Ok();
  }

  Status emit_one(const Octant& leaf, uint64_t key) {
    ++count;
    if (!wants_leaves()) return Status::Ok();
    uint64_t id = 0;
    WEAVER_RETURN_IF_ERROR(t.rank(key, &id));
    if (id < from) return Status::Ok();
    if (on_run) return add_run(id, id + 1);
    if (listed == limit) return next = id, Status::Ok();
    ++listed;
    (*on_leaf)(leaf, id);
    return Status::Ok();
  }

  Status emit_all(uint64_t key, uint64_t first, uint64_t end) {
    count += end - first;
    if (!wants_leaves()) return Status::Ok();
    if (first < from) {  // the page starts inside this subtree
      first = from;
      WEAVER_RETURN_IF_ERROR(t.select(first, &key, nullptr));
    }
    if (on_run) return add_run(first, end);
    BTreeCursor c;
    WEAVER_RETURN_IF_ERROR(t.seek_cursor(key, &c));
    for (uint64_t id = first; id < end; ++id) {
      if (listed == limit) return next = id, Status::Ok();
      if (!c.valid()) return Status::Corruption(t.file_name() + ": ranks disagree with a scan");
      ++listed;
      (*on_leaf)(octant_from_key(c.key()), id);
      WEAVER_RETURN_IF_ERROR(c.next());
    }
    return Status::Ok();
  }

  // Runs that touch are handed on as one.
  Status add_run(uint64_t first, uint64_t end) {
    if (first == run_end && run_end > run_first) return run_end = end, Status::Ok();
    WEAVER_RETURN_IF_ERROR(flush_run());
    run_first = first, run_end = end;
    return Status::Ok();
  }
  Status flush_run() {
    if (run_end == run_first) return Status::Ok();
    const uint64_t a = run_first, b = run_end;
    run_first = run_end = 0;
    return (*on_run)(a, b);
  }
};

// The box as the walk takes it, checked: a box drawn to the domain's far
// edge ends on the address space's far face (tick 2^20), where no pixel
// is; every leaf that reaches that face holds the pixel before it, so the
// box may reach it.
Status checked_box(const TickBox& asked, TickBox* box) {
  *box = asked;
  for (uint32_t* c : {&box->lo.x, &box->lo.y, &box->lo.z, &box->hi.x, &box->hi.y, &box->hi.z}) {
    if (*c == kRootEdge) *c = kRootEdge - 1;
  }
  const uint32_t lo[3] = {box->lo.x, box->lo.y, box->lo.z};
  const uint32_t hi[3] = {box->hi.x, box->hi.y, box->hi.z};
  for (int a = 0; a < 3; ++a) {
    if (lo[a] > hi[a]) {
      return Status::InvalidArgument("box lower corner exceeds its upper corner on axis " +
                                     std::string(1, "xyz"[a]));
    }
  }
  if (!pixel_is_valid(box->lo) || !pixel_is_valid(box->hi)) {
    return Status::InvalidArgument("box reaches outside the address space [0, 1048576)");
  }
  return Status::Ok();
}

}  // namespace

Status locate(BTree& octants, Coord p, LocateResult* out) {
  *out = LocateResult{};
  if (!pixel_is_valid(p)) {
    return Status::InvalidArgument("point (" + std::to_string(p.x) + " " + std::to_string(p.y) +
                                   " " + std::to_string(p.z) +
                                   ") is outside the address space [0, 1048576)");
  }
  uint64_t key = 0;
  bool found = false;
  WEAVER_RETURN_IF_ERROR(octants.floor(pixel_key(p), &key, nullptr, &found));
  if (!found) return Status::Ok();
  const Octant leaf = octant_from_key(key);
  if (!octant_contains_point(leaf, p)) return Status::Ok();
  out->inside = true;
  out->leaf = leaf;
  return octants.rank(key, &out->element_id);
}

Status range_query(BTree& octants, const TickBox& asked, uint64_t* count,
                   const std::function<void(const Octant&, uint64_t)>& on_leaf) {
  *count = 0;
  TickBox box;
  WEAVER_RETURN_IF_ERROR(checked_box(asked, &box));
  RangeWalk walk{octants, box};
  if (on_leaf) walk.on_leaf = &on_leaf;
  if (octants.size() == 0) return Status::Ok();
  WEAVER_RETURN_IF_ERROR(walk.visit(octant_root()));
  *count = walk.count;
  return Status::Ok();
}

Status range_page(BTree& octants, const TickBox& asked, uint64_t from, uint64_t limit,
                  const std::function<void(const Octant&, uint64_t)>& on_leaf, uint64_t* next) {
  *next = UINT64_MAX;
  TickBox box;
  WEAVER_RETURN_IF_ERROR(checked_box(asked, &box));
  RangeWalk walk{octants, box, &on_leaf};
  walk.from = from, walk.limit = limit;
  if (octants.size() > 0) WEAVER_RETURN_IF_ERROR(walk.visit(octant_root()));
  *next = walk.next;
  return Status::Ok();
}

Status range_runs(BTree& octants, const TickBox& asked,
                  const std::function<Status(uint64_t, uint64_t)>& on_run) {
  TickBox box;
  WEAVER_RETURN_IF_ERROR(checked_box(asked, &box));
  RangeWalk walk{octants, box, nullptr, &on_run};
  if (octants.size() > 0) WEAVER_RETURN_IF_ERROR(walk.visit(octant_root()));
  return walk.flush_run();
}

}  // namespace weaver
