#include "construct/construct.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <vector>

#include "construct/carve.h"
#include "construct/descent.h"
#include "construct/estimate.h"
#include "construct/least_step.h"
#include "construct/subtree_balance.h"
#include "construct/subtree_run.h"
#include "construct/subtree_slots.h"
#include "db/database.h"
#include "model/geo_frame.h"
#include "model/velocity_model.h"
#include "modeldb/model_identity.h"
#include "modeldb/open_model.h"
#include "schema/octant.h"

namespace weaver {
namespace {

// The deepest block level tried when fitting the domain: 2^10 blocks a side.
constexpr int kMaxBlockLevel = 10;
// The blocks of a domain that no blocks tile exactly (rounded up to them).
constexpr int kRoundedBlockLevel = 7;
// Subtrees are cut so that the estimate puts about this many leaves in
// each: enough to keep a thread busy for a while, few enough to balance.
constexpr double kLeavesPerSubtree = 4096;
// A balanced construct descends again the leaves around each subtree, a
// share that falls as the subtree grows, but the balance of a larger one
// leaves the cache: at 1 Hz, subtrees of 32K to 256K estimated leaves
// descended 27% again against 36% for 4K to 32K, and took 10-20% longer.
// So its subtrees hold 4K to 32K estimated leaves (the model's small
// features add up to 3x; past its room a subtree is visited again as its 8
// children).
constexpr double kLeastLeavesPerBalancedSubtree = 4096;
// A model that loads its focus (a model database) loads the model around
// each subtree grown by twice its coarsest leaf, and reads the model twice
// over where subtrees are small: where the subtrees' rooms are pooled (so a
// large one does not overflow its room and is not descended again as its
// eighths), its subtrees are a level coarser.  At 1 Hz from the 100 m model
// database: 0.929x the time on one thread at the default --memory (0.957x
// in an earlier run), 0.930x on two at --memory 1G (on two at 256M,
// unpooled, 1.24x).
constexpr double kLeastLeavesPerFocusedSubtree = 8 * kLeastLeavesPerBalancedSubtree;
// Where the estimate puts at most this many leaves in an octant coarser
// than the subtrees' level, a balanced construct takes it whole as one
// subtree: fewer leaves around the subtrees are descended again (at 1 Hz
// 9.5% of the leaves instead of 19.3%).  Not more: at 2 Hz, where the
// estimate is a third of the leaves, larger ones gained nothing (128K:
// 1.00x the time, with the pool of leaves that lets them finish).
constexpr double kMostLeavesPerWholeSubtree = 65536;
// The least even share of the subtrees' room (leaves) at which they share a
// pool (subtree_rooms): --memory 512M and up on two threads, 256M on one.
constexpr uint64_t kLeastPooledRoom = uint64_t{1} << 18;
// The same for a balanced construct from a model database, whose plan counts
// the balance's buffers where it pools (ConstructMemory): 256M and up on
// two threads, and never below kLeastFocusedPooledBudget.  Its pooled
// subtrees are a level coarser (list_subtrees): at 1 Hz from the 100 m
// model database at 256M on two threads, 0.91x the time (farm-bench, 9
// pairs) with the readers' share cut from a half to 5/16 to make room for
// the balance.
constexpr uint64_t kLeastFocusedPooledRoom = uint64_t{1} << 17;
// Below it the parts outside the plan (the code, the stacks, the allocator's
// free blocks) and the octant table's pool, the same at any budget, left
// too little: pooled at 128M on one thread, the 1 Hz construct peaked at
// 124,660 to 130,492 KiB of the 131,072 (at 256M on two, 228,568 to
// 237,396 of 262,144).
constexpr uint64_t kLeastFocusedPooledBudget = 256ull << 20;
// The balance's buffers a worker holds (subtree_balance.h: the leaves
// collected around its subtree, their merge with its own, the ripple's asks
// and candidates), bytes a leaf of the largest subtree it balanced: up to
// 44 measured at 1 Hz from the 100 m model database (22.5 MB a thread
// beside a subtree of 519K leaves).
constexpr uint64_t kBalanceBytesPerLeaf = 48;
// Subtrees in flight per thread: workers run ahead of the writer.
constexpr size_t kSubtreesPerThread = 8;

// New leaves take the model's material at their centre where weaver balance
// would (it opens the model the table names; a grid file it cannot name),
// else their parent's: the balanced table is the one balance writes.
bool fills_material(const ConstructOptions& o) { return o.model != "grid"; }

// A worker's visit of one subtree: the descent, then (balanced) its balance
// against the leaves around it.  An overflowing subtree is left as it is.
class SubtreeVisitor {
 public:
  SubtreeVisitor(const ConstructOptions& o, const Descent& d)
      : descent_(d), balanced_(o.balanced), balancer_(d, fills_material(o)) {}
  void visit(Slot* s) {
    descent_.visit_subtree(s->root, s->room, &s->leaves);
    if (s->leaves.overflow) return;
    const bool carved = descent_.plan().carved;
    if (balanced_) {
      s->descended = s->leaves.keys.size();
      balancer_.balance(s->root, &s->leaves);
    }
    // Air goes after the balance: what remains of a balanced octree is
    // balanced, and its dangling nodes' anchors stay anchored (balanced
    // among the remaining elements alone, a dangling node's anchor may
    // dangle too where air fills the space between).
    if (carved) {
      s->leaves.flatten(descent_.payload_bytes());
      carve_leaves(descent_.plan(), descent_.payload_bytes(), &s->leaves, &s->air, &s->cut);
    }
  }
  uint64_t neighbours() const { return balancer_.neighbours_collected(); }

 private:
  const Descent& descent_;
  bool balanced_;
  SubtreeBalancer balancer_;
};

// The level of the subtrees: as many levels below the blocks as put about
// kLeavesPerSubtree estimated leaves in each (balanced: at least
// kLeastLeavesPerBalancedSubtree, or, focused, kLeastLeavesPerFocusedSubtree).
int subtree_level(const ConstructOptions& o, const ConstructPlan& p, bool focused) {
  const double blocks = double(p.blocks[0]) * p.blocks[1] * p.blocks[2];
  double per_subtree = p.estimated_elements / blocks;
  int level = p.block_level;
  if (o.balanced) {
    const double least = focused ? kLeastLeavesPerFocusedSubtree : kLeastLeavesPerBalancedSubtree;
    while (level < o.max_level && per_subtree >= 8 * least) {
      per_subtree /= 8, ++level;
    }
    return level;
  }
  while (level < o.max_level && per_subtree > kLeavesPerSubtree) per_subtree /= 8, ++level;
  return level;
}

// A parallel run's part: the subtrees whose share of the estimate begins in
// it.
int rank_of_subtree(const ConstructOptions& o, const ZOrderShare& share, const Octant& root) {
  if (o.shards <= 1) return 0;
  const double f = share.fraction_before(octant_key(root)) * o.shards;
  return std::min(static_cast<int>(f), o.shards - 1);
}

// The subtrees in flight on `threads` workers.
size_t window_of(int threads) { return kSubtreesPerThread * std::max(1, threads); }

// The even share of the subtrees' room (leaves): `bytes` over the subtrees
// in flight, a leaf taking its key and the largest payload.
uint64_t even_room(uint64_t bytes, int threads) {
  return std::clamp<uint64_t>(bytes / window_of(threads) / (8 + Descent::kMaxPayloadBytes), 64,
                              uint64_t{1} << 19);
}

// The leaves a subtree's visit may hold (leaf_room.h; past them it is
// visited again as its 8 children).
struct SubtreeRooms {
  size_t own = 0, most = 0;  // each subtree's own room, and the most it may take
  uint64_t spare = 0;        // the pool the subtrees in flight share
  uint64_t even = 0;         // the budget's room for them over their number
};

// The subtrees in flight share the budget's room for them evenly, each
// owning half its even share and lending the other half to the pool; one
// takes at most 4 even shares.  Only where the even share is
// kLeastPooledRoom or more: the balance's buffers (one set a thread, about
// 70 bytes a leaf of the largest subtree it balanced, not in the budget's
// plan) grow with the largest subtree, and at --memory 64M subtrees of 4
// even shares took the 2 Hz construct to 101 MB.  Below it each room is
// fixed, no pool.  The tests' o.subtree_leaves is a fixed room, with
// o.subtree_pool a pool of that many leaves.
SubtreeRooms subtree_rooms(const ConstructOptions& o, const ConstructMemory& memory) {
  if (o.subtree_leaves > 0) {
    return {o.subtree_leaves, 4 * o.subtree_leaves, o.subtree_pool, o.subtree_leaves};
  }
  const uint64_t even = even_room(memory.subtrees, o.threads);
  if (!memory.pooled) return {even, even, 0, even};
  return {even / 2, 4 * even, window_of(o.threads) * (even - even / 2), even};
}

// Whether the subtrees' rooms are pooled: a model database's subtrees are
// then a level coarser.  (The tests' fixed rooms: where they are as large
// as a budget's that pools.)
bool pooled_rooms(const ConstructOptions& o, const ConstructMemory& memory) {
  return o.subtree_leaves > 0 ? o.subtree_leaves >= kLeastPooledRoom : memory.pooled;
}

// The estimated leaves of a subtree taken whole: kMostLeavesPerWholeSubtree,
// or less where the rooms are small (the estimate may be a third of the
// leaves, and a subtree past its room is descended twice).
double most_whole_leaves(const ConstructOptions& o, const ConstructMemory& memory) {
  return std::min<double>(kMostLeavesPerWholeSubtree, double(subtree_rooms(o, memory).even) / 8);
}

// The domain's subtrees: those of subtree_level(), and, balanced, coarser
// octants taken whole where the estimate puts at most most_whole_leaves()
// in them; none for a model that loads its focus (VelocityModel::loads_focus),
// whose subtrees are a level coarser where their rooms are pooled.
SubtreeList list_subtrees(const ConstructOptions& o, const ConstructPlan& p, const Descent& descent,
                          const ZOrderShare& share, const ConstructMemory& memory) {
  if (!o.balanced) return SubtreeList(descent, p, subtree_level(o, p, false));
  if (descent.model().loads_focus()) {
    return SubtreeList(descent, p, subtree_level(o, p, pooled_rooms(o, memory)));
  }
  const double total = p.estimated_elements, most = most_whole_leaves(o, memory);
  return SubtreeList(
      descent, p, subtree_level(o, p, false), [&share, total, most](const Octant& x) {
        const uint64_t k = octant_key(x);
        const double f =
            share.fraction_before(octant_key_subtree_end(x)) - share.fraction_before(k);
        return f * total <= most;
      });
}

// Where o.shard's file lies among the shards: the ranks given a subtree
// write one each (a subtree has a leaf at least).
ShardPlace place_of_shard(const ConstructOptions& o, const ConstructPlan& p, const Descent& descent,
                          const ZOrderShare& share, const ConstructMemory& memory) {
  std::vector<bool> has(o.shards, false);
  SubtreeList subtrees = list_subtrees(o, p, descent, share, memory);
  for (Octant root; subtrees.next(&root);) has[rank_of_subtree(o, share, root)] = true;
  return shard_place_among(has, o.shard);
}

// Appends a subtree's leaves to the table a run at a time, and notes the
// least edge / vp among them in *r: what an explicit solver's time step is
// a Courant number times.  Each run is read for it while it is in the
// cache for the append.  Leaves in pieces (a balance split some) are
// appended where they lie when a piece is long, and short pieces copied
// into a buffer that stays in the cache, a run of them at a time (each
// piece copied was 2.9% of the 2 Hz construct's samples).
Status append_leaves(const SubtreeLeaves& leaves, size_t bytes, double tick_m, BTree& out,
                     ConstructResult* r) {
  constexpr size_t kRun = 4096, kLongPiece = 512;
  // (An empty subtree still tells the table it changed, as it always has.)
  if (leaves.elements == 0) return out.append_batch(leaves.keys.data(), leaves.payloads.data(), 0);
  uint64_t done = 0;
  auto append = [&](const uint64_t* keys, const std::byte* payloads, size_t n) {
    note_least_step(keys, payloads, n, bytes, tick_m, r->elements + done, &r->least_dt,
                    &r->least_dt_element);
    done += n;
    return out.append_batch(keys, payloads, n);
  };
  auto append_runs = [&](const uint64_t* keys, const std::byte* payloads, size_t n) {
    for (size_t at = 0; at < n; at += kRun) {
      WEAVER_RETURN_IF_ERROR(append(keys + at, payloads + at * bytes, std::min(n - at, kRun)));
    }
    return Status::Ok();
  };
  if (leaves.pieces.empty()) {
    return append_runs(leaves.keys.data(), leaves.payloads.data(), leaves.keys.size());
  }
  thread_local std::vector<uint64_t> keys;
  thread_local std::vector<std::byte> payloads;
  keys.resize(kRun), payloads.resize(kRun * bytes);
  size_t staged = 0;
  WEAVER_RETURN_IF_ERROR(
      leaves.for_each_run(bytes, [&](const uint64_t* k, const std::byte* b, size_t n) -> Status {
        if (n >= kLongPiece) {
          if (staged > 0) WEAVER_RETURN_IF_ERROR(append(keys.data(), payloads.data(), staged));
          staged = 0;
          return append_runs(k, b, n);
        }
        while (n > 0) {
          const size_t take = std::min(n, kRun - staged);
          std::memcpy(keys.data() + staged, k, take * sizeof *k);
          std::memcpy(payloads.data() + staged * bytes, b, take * bytes);
          staged += take, k += take, b += take * bytes, n -= take;
          if (staged == kRun) {
            WEAVER_RETURN_IF_ERROR(append(keys.data(), payloads.data(), staged));
            staged = 0;
          }
        }
        return Status::Ok();
      }));
  return staged == 0 ? Status::Ok() : append(keys.data(), payloads.data(), staged);
}

// Visits the domain's subtrees on o.threads workers (or on this thread for
// one) and appends their leaves in Z-order.  A subtree with more leaves
// than its room allows is visited again as its 8 children, so memory stays bounded
// wherever the model is dense.
Status write_subtrees(const ConstructOptions& o, const ConstructPlan& p, const Descent& descent,
                      const ConstructMemory& memory, const ZOrderShare& share, BTree& out,
                      ConstructResult* r) {
  const int threads = std::max(1, o.threads);
  const SubtreeRooms rooms = subtree_rooms(o, memory);
  SubtreeSlots slots(rooms.own, rooms.most, rooms.spare, descent.payload_bytes());
  std::vector<std::unique_ptr<SubtreeVisitor>> visitors;
  for (int i = 0; i < threads; ++i) {
    visitors.push_back(std::make_unique<SubtreeVisitor>(o, descent));
  }
  SubtreeList subtrees = list_subtrees(o, p, descent, share, memory);
  auto next = [&](Octant* root) {
    while (subtrees.next(root)) {
      if (rank_of_subtree(o, share, *root) == o.shard) return true;
    }
    return false;
  };
  auto visit = [&](int i, Slot* s) { visitors[i]->visit(s); };
  auto write = [&](const Slot& s) {
    ++r->subtrees;
    const SubtreeLeaves& leaves = s.leaves;
    WEAVER_RETURN_IF_ERROR(append_leaves(leaves, descent.payload_bytes(), p.tick_m, out, r));
    leaves.add_to(r);
    r->descended += s.descended;
    r->air += s.air;
    r->cut += s.cut;
    if (o.progress && leaves.elements > 0) {
      o.progress(r->elements, share.fraction_before(leaves.last_key()));
    }
    return Status::Ok();
  };
  auto over = [&] { ++r->subtrees, ++r->subtrees_over; };
  SubtreeRun run(window_of(threads), slots, next, visit, write, over);
  const Status st = run.go(threads);
  for (const auto& v : visitors) r->neighbours += v->neighbours();
  return st;
}

// The coarsest blocks that tile the domain exactly: the fewest, n, along its
// longest side such that every side is a whole number of blocks of edge
// longest / n.  The root holds the next power of two of them (level: its
// exponent), so it is the longest side when n is a power of two (100 x 100 x
// 37.5 km: 8 x 8 x 3 blocks of 12.5 km) and longer otherwise (100 x 80 x 37.5
// km: 40 x 32 x 15 blocks of 2.5 km in a root of 64, 160 km).  False when no n
// up to 2^kMaxBlockLevel does.
bool exact_blocks(const std::array<double, 3>& domain, int* level, double* block) {
  const double longest = std::max({domain[0], domain[1], domain[2]});
  for (uint32_t n = 1; n <= (1u << kMaxBlockLevel); ++n) {
    const double b = longest / n;
    bool whole = true;
    for (double l : domain) whole = whole && std::abs(l / b - std::round(l / b)) < 1e-9;
    if (whole) {
      *block = b;
      *level = std::bit_width(n - 1);  // 2^level >= n
      return true;
    }
  }
  return false;
}

bool is_rfile(const std::string& model) { return model.rfind("rfile:", 0) == 0; }

// The ground: its surface, the top's elevation, how the model reads z.
Status plan_ground(const ConstructOptions& o, const VelocityModel& model, uint64_t surface_bytes,
                   ConstructPlan* p) {
  const std::string source = !o.surface.empty()  ? o.surface
                             : is_rfile(o.model) ? o.model
                                                 : std::string("flat");
  SurfaceSource s;
  WEAVER_RETURN_IF_ERROR(parse_surface_source(source, &s));
  s.crs = o.surface_crs;
  const std::string z = o.model_z.empty() ? (is_rfile(o.model) ? "elevation" : "depth") : o.model_z;
  WEAVER_RETURN_IF_ERROR(parse_model_z(z, &p->ground.model_z));
  GeoFrame geo;
  const std::string geo_text = o.geo.empty() ? model.geo() : o.geo;
  if (!geo_text.empty()) WEAVER_RETURN_IF_ERROR(GeoFrame::parse(geo_text, &geo));
  // A plan planned again (weaver mesh plans, then construct plans once
  // more) keeps the surface it read: a DEM is read once a run.
  std::shared_ptr<const Surface> surface;
  if (p->surface != nullptr && p->surface_source == s.text && p->surface_crs == s.crs) {
    surface = p->surface;
  } else {
    std::unique_ptr<Surface> loaded;
    WEAVER_RETURN_IF_ERROR(
        load_surface(s, geo_text.empty() ? nullptr : &geo, surface_bytes, &loaded));
    surface = std::move(loaded);
  }
  p->surface_source = s.text;
  p->surface_crs = s.crs;
  double top = std::isnan(o.top_elevation) ? 0 : o.top_elevation;
  if (surface) {
    const double highest = surface->highest();
    if (std::isnan(o.top_elevation)) {
      top = std::ceil(highest / p->tick_m - 1e-9) * p->tick_m;
    } else if (highest > top) {
      char buf[200];
      std::snprintf(buf, sizeof buf, "the ground rises to %.2f m, above --top-elevation %g m",
                    highest, top);
      return Status::InvalidArgument(buf);
    }
    p->surface_outside = surface->outside(p->domain_m[0], p->domain_m[1]);
    if (surface->filled > 0 && p->surface_outside.empty()) {
      // Said in the plan: the nearest valid ground stood in for NODATA.
      p->surface_outside = std::to_string(surface->filled) +
                           " NODATA points of the surface took the nearest valid ground";
    }
  }
  if (!std::isfinite(top) || std::abs(top) > 1e7)
    return Status::InvalidArgument("--top-elevation must be a finite number of metres");
  p->ground.top_elevation = top;
  p->surface = std::move(surface);
  p->ground.surface = p->surface.get();
  p->carved = p->surface != nullptr;
  return Status::Ok();
}

// The model as the mesh's frame asks it: under the ground, or as it is
// where the top is flat at elevation 0 (today's meshes, unchanged).
void ground_model(const ConstructPlan& p, std::unique_ptr<VelocityModel>* model) {
  if (!p.carved && p.ground.top_elevation == 0) return;
  *model = std::make_unique<GroundedModel>(std::move(*model), p.ground);
}

}  // namespace

Status plan_construct(const ConstructOptions& o, ConstructPlan* p) {
  for (double l : o.domain_m) {
    if (!(l > 0) || !std::isfinite(l))
      return Status::InvalidArgument("domain sizes must be positive");
  }
  if (!(o.freq > 0) || !(o.ppw > 0) || o.vs_min < 0) {
    return Status::InvalidArgument("--freq and --ppw must be positive, --vs-min not negative");
  }
  if (o.min_level < 0 || o.max_level > kMaxLevel || o.min_level > o.max_level) {
    return Status::InvalidArgument("levels must satisfy 0 <= min level <= max level <= 20");
  }
  const double longest = std::max({o.domain_m[0], o.domain_m[1], o.domain_m[2]});
  double block = 0;
  p->rounded_up = !exact_blocks(o.domain_m, &p->block_level, &block);
  if (p->rounded_up) {
    // Blocks of 1/128 of the longest side: each side grows by less than 0.8%
    // of it, and there are at most 2M blocks (finer ones, such as 1/1024,
    // planned up to 10^9 of them, most of them leaves at any frequency).
    p->block_level = kRoundedBlockLevel;
    block = longest / (1 << kRoundedBlockLevel);
  }
  p->root_edge_m = block * (1 << p->block_level);
  p->tick_m = p->root_edge_m / kRootEdge;
  for (int a = 0; a < 3; ++a) {
    p->blocks[a] = static_cast<uint32_t>(std::ceil(o.domain_m[a] / block - 1e-9));
    p->domain_m[a] = p->blocks[a] * block;
  }
  if (p->block_level > o.max_level) {
    return Status::InvalidArgument("the domain needs blocks of level " +
                                   std::to_string(p->block_level) + ", finer than --max-level");
  }
  const ConstructMemory memory(o);
  std::unique_ptr<VelocityModel> model;
  WEAVER_RETURN_IF_ERROR(
      open_velocity_model(o.model, o.grid_file, memory.model, std::max(1, o.threads), &model));
  WEAVER_RETURN_IF_ERROR(plan_ground(o, *model, memory.surface, p));
  ground_model(*p, &model);
  p->model = model->describe();
  p->outside = model->outside(p->domain_m);
  if (!p->outside.empty() && o.outside_error) {
    return Status::NotFound(p->outside +
                            " (without --outside error, points there take the "
                            "values of the nearest model cell)");
  }
  if (!p->surface_outside.empty() && o.outside_error) {
    return Status::NotFound(p->surface_outside +
                            " (without --outside error, the ground there is the grid's "
                            "nearest edge)");
  }
  const ConstructEstimate e = estimate_construct(o, *p, *model);
  p->estimated_elements = e.elements;
  p->estimated_disk_bytes = e.disk_bytes;
  p->estimated_least_disk_bytes = e.least_disk_bytes;
  return Status::Ok();
}

ConstructMemory::ConstructMemory(const ConstructOptions& o)
    : ConstructMemory(o.memory, o.threads, o.balanced && names_model_database(o.model)) {}

ConstructMemory::ConstructMemory(MemoryBudget budget, int threads, bool focused_balance)
    : plan(budget) {
  // A sorted append touches only the right spine of the table.  (With an
  // eighth, not a sixteenth, the shares that fill left only the flat
  // ground's unused eighth for what the plan does not count, and construct
  // from a model database at --memory 64M on two threads peaked at 64,744
  // and 65,888 KiB of the budget's 65,536; now 61,032 and 61,632, and no
  // slower.)
  table_pool = plan.take("octant table pool", 1, 16, 8ull << 20);
  // Leaves of the subtrees visited ahead of the writer (kSubtreesPerThread
  // a thread); each is capped, so a small share only means smaller caps.
  subtrees = plan.take("subtrees in flight", 1, 4, 256ull << 20);
  const uint64_t even = even_room(subtrees, threads);
  if (focused_balance && even >= kLeastFocusedPooledRoom &&
      budget.bytes() >= kLeastFocusedPooledBudget) {
    // The balance's buffers grow with the largest subtree, 4 even shares
    // where pooled: counted here, at most 3/16 of the budget.  (Outside the
    // plan, the pooled subtrees took a construct from a model database to
    // 270 MB at --memory 256M on two threads; an analytic model leaves the
    // readers' half unused, where they lie.)  The readers keep 5/16: at a
    // quarter, their regions could not hold the coarser subtrees' boxes
    // (every point then searched the table: the 1 Hz construct took 4x the
    // time; visited as their children instead, 1.2x).
    pooled = true;
    balance = plan.record("subtree balance",
                          uint64_t(std::max(1, threads)) * 4 * even * kBalanceBytesPerLeaf);
    model = plan.take_budget("model readers", 5, 16);
  } else {
    pooled = even >= kLeastPooledRoom;
    // A model read from storage (modeldb/db_model.h): each worker's table
    // cache and the decoded model octants around its subtree.
    model = plan.take_budget("model readers", 1, 2);
  }
  // The ground's grid, whole, with its pyramid: 12 bytes a point (a 1000
  // x 1000 DEM takes 12 MB of the 128 MB this leaves at --memory 1G).
  surface = plan.take("surface", 1, 8);
}

namespace {

TableOptions octant_table_options(const ConstructOptions& o, const ConstructPlan& p,
                                  const VelocityModel& model) {
  TableOptions t;
  t.key_kind = KeyKind::kOctant;
  t.schema = material_schema(model.has_q());
  if (p.carved) {
    std::string error;
    t.schema =
        *RecordSchema::parse(std::string(model.has_q() ? "vp:f32,vs:f32,rho:f32,qp:f32,qs:f32"
                                                       : "vp:f32,vs:f32,rho:f32") +
                                 ",solid:f32",
                             &error);
  }
  t.packed = o.packed;
  return t;
}

// The leaves of o's part (all, or one shard's) into table, and the table's
// metadata: units, level counts, the model and the rule.
Status write_octree(const ConstructOptions& o, const ConstructPlan& p, const VelocityModel& model,
                    const ConstructMemory& memory, BTree& table, ConstructResult* r,
                    ShardPlace* place = nullptr) {
  const Descent descent(o, p, model);
  // The estimate along the Z-order: progress, the shards' parts, and the
  // balanced subtrees taken whole.
  ZOrderShare share;
  if (o.progress || o.shards > 1 || (o.balanced && !model.loads_focus())) {
    estimate_construct(o, p, model, &share);
  }
  if (place != nullptr) *place = place_of_shard(o, p, descent, share, memory);
  WEAVER_RETURN_IF_ERROR(write_subtrees(o, p, descent, memory, share, table, r));
  Units u;
  u.tick_m = p.tick_m;
  u.geo = o.geo.empty() ? model.geo() : o.geo;
  char rule[160];
  std::snprintf(rule, sizeof rule, ";freq=%.17g;ppw=%.17g;vs_min=%.17g", o.freq, o.ppw, o.vs_min);
  // A model database is named by its identity (read once, here: a plan is
  // made twice), never by its path.
  std::string model_name = o.model;
  if (names_model_database(o.model)) {
    WEAVER_RETURN_IF_ERROR(model_table_identity(model_database_dir(o.model), &model_name));
  }
  const std::string model_meta = ";model=" + model_name + rule;
  std::string ground_meta;
  if (p.carved || p.ground.top_elevation != 0) {
    char buf[160];
    std::snprintf(buf, sizeof buf, ";top_elevation_m=%.17g;model_z=%s;surface_edge=%.17g",
                  p.ground.top_elevation, model_z_name(p.ground.model_z), o.surface_edge_m);
    ground_meta = ";surface=" + p.surface_source + buf;
    if (p.carved && o.surface_crs == SurfaceCrs::kLonLat) ground_meta += ";surface_crs=lonlat";
  }
  std::string proj = model.projection();
  if (!proj.empty()) {
    // Kept as text: ';' separates the metadata's items, so none may be in it.
    std::replace(proj.begin(), proj.end(), ';', ' ');
    ground_meta += ";proj=" + proj;
  }
  table.set_metadata(units_to_metadata(u) + levels_to_metadata(r->levels) + model_meta +
                     ground_meta);
  return Status::Ok();
}

// The plan, and the model the workers sample (one reader a thread).
Status plan_and_open(const ConstructOptions& o, const ConstructMemory& memory, ConstructPlan* p,
                     std::unique_ptr<VelocityModel>* model) {
  WEAVER_RETURN_IF_ERROR(plan_construct(o, p));
  WEAVER_RETURN_IF_ERROR(
      open_velocity_model(o.model, o.grid_file, memory.model, std::max(1, o.threads), model));
  ground_model(*p, model);
  return Status::Ok();
}

}  // namespace

Status construct_octree(const std::string& db_dir, const ConstructOptions& o, ConstructPlan* p,
                        ConstructResult* r) {
  *r = ConstructResult{};
  const ConstructMemory memory(o);
  std::unique_ptr<VelocityModel> model;
  WEAVER_RETURN_IF_ERROR(plan_and_open(o, memory, p, &model));
  WEAVER_RETURN_IF_ERROR(check_construct_fits(o, planned_estimate(*p), db_dir));
  std::unique_ptr<Database> own;
  Database* db = o.writer;
  if (db == nullptr) {
    WEAVER_RETURN_IF_ERROR(Database::open(db_dir, Database::Mode::kWrite, true, &own));
    db = own.get();
  }
  std::unique_ptr<BTree> table;
  std::string file;
  WEAVER_RETURN_IF_ERROR(db->create_table(kOctantTable, octant_table_options(o, *p, *model),
                                          memory.table_pool, &table, &file));
  const Status st = write_octree(o, *p, *model, memory, *table, r);
  WEAVER_RETURN_IF_ERROR(o.stage ? db->stage(kOctantTable, file, table, st)
                                 : db->publish(kOctantTable, file, table, st));
  r->table_bytes = table->file_bytes();
  return Status::Ok();
}

Status construct_shard(const std::string& db_dir, const ConstructOptions& o,
                       const std::string& file, ConstructPlan* p, ConstructResult* r,
                       ShardEntry* entry) {
  *r = ConstructResult{};
  *entry = ShardEntry{file};
  const ConstructMemory memory(o);
  std::unique_ptr<VelocityModel> model;
  WEAVER_RETURN_IF_ERROR(plan_and_open(o, memory, p, &model));
  std::unique_ptr<BTree> table;
  WEAVER_RETURN_IF_ERROR(create_shard_table(db_dir, file, octant_table_options(o, *p, *model),
                                            memory.table_pool, &table));
  ShardPlace place;
  Status st = write_octree(o, *p, *model, memory, *table, r, &place);
  return finish_shard(db_dir, table, st, place, entry, &r->table_bytes);
}

}  // namespace weaver
