// Construct's descent over one subtree, and the subtrees that cut the domain
// into tasks for worker threads.
//
// A subtree is visited depth first in Z-order: an octant whose least Vs over
// its 27 sample points (the corners, edge midpoints, face centres and centre)
// asks for a finer edge (or that lies above --min-level) is split, any other
// is a leaf, written with the material at its centre.  The samples are taken
// only where they matter: where the model bounds the Vs of an octant's whole
// box (VelocityModel::vs_bounds) and the bounds settle the question (both
// ask for a split, or neither does), the samples, which lie in the box,
// would settle it the same way.  Most octants are settled so: the bulk of
// the rock and sediment, the inside of inclusions.  A split whose children
// must mostly be sampled evaluates its 5 x 5 x 5 lattice once, 125 samples
// for the 216 of the children's own lattices.  Where the bounds show every
// leaf under an octant to be of one level (each level above it splits at
// their upper bound, it is a leaf at their lower), those leaves are written
// as a block, their materials from lattices of their centres, none judged
// alone (64% of the descent's leaves of the basin at 0.5 Hz).  Subtrees are
// independent, so workers may visit them in any order; their leaves are
// written in Z-order (construct.cc), and the table is the same for any
// number of threads.
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <functional>
#include <vector>

#include "construct/carve.h"
#include "construct/construct.h"
#include "construct/leaf_room.h"
#include "model/velocity_model.h"
#include "schema/octant.h"
#include "schema/status.h"
#include "util/uninit_vector.h"

namespace weaver {

// The leaves of one subtree, in key order, and what construct reports of them.
struct SubtreeLeaves {
  // (Grown, then written: uninit_vector.h.)
  UninitVector<uint64_t> keys;
  UninitVector<std::byte> payloads;  // vp, vs, rho [, qp, qs] as f32 (material_schema)
  // Carved: each leaf's side of the ground as the descent found it (kCut
  // also for a leaf nobody judged, to be found by the carve).
  std::vector<GroundSide> sides;
  LevelCounts levels{};
  uint64_t elements = 0;
  uint64_t blocked = 0;  // of the descent's leaves, those of whole blocks
  double smallest_edge_m = 0, largest_edge_m = 0, worst_ppw = 0;
  // The least Vs of the leaves of each level (the worst points per
  // wavelength follow from it once the subtree is done, without a division
  // for every leaf).
  std::array<double, kMaxLevel + 1> least_vs{};
  // The subtree's root, and for each side of it the edge (ticks) of the
  // largest leaf touching it: how far its balance looks outside.
  Octant root;
  std::array<uint32_t, 3> border_lo{}, border_hi{};
  LeafSpan span;          // carved: what the kept leaves span (carve.h)
  bool overflow = false;  // more leaves than its room allows: visit the children instead
  // Where the balance split leaves (subtree_balance.h), the leaves in key
  // order are runs of keys / payloads / sides and of the leaves it added
  // (added_*), in turn, as `pieces` say; with no pieces, keys and payloads
  // are the leaves.  The writer reads them so: copying the whole subtree
  // to splice the new leaves in was 3.4% of the 2 Hz construct's samples.
  struct Piece {
    bool added;  // of added_*, not of keys
    size_t begin, end;
  };
  std::vector<Piece> pieces;
  UninitVector<uint64_t> added_keys;
  UninitVector<std::byte> added_payloads;
  std::vector<GroundSide> added_sides;

  void clear();
  // The keys and payloads reserved for `leaves` where they have less: a
  // room grown from the pool (leaf_room.h) grows them by its grants, not by
  // doubling, which held up to twice the leaves the pool lent.
  void fit(size_t leaves, size_t payload_bytes) {
    if (keys.capacity() >= leaves) return;
    keys.reserve(leaves);
    payloads.reserve(leaves * payload_bytes);
  }
  // run(keys, payloads, n) for each run of the leaves in key order
  // (payloads of `bytes` each); its first error stops them.
  template <class Run>
  Status for_each_run(size_t bytes, const Run& run) const {
    if (pieces.empty()) return run(keys.data(), payloads.data(), keys.size());
    for (const Piece& p : pieces) {
      const uint64_t* k = (p.added ? added_keys : keys).data() + p.begin;
      const std::byte* b = (p.added ? added_payloads : payloads).data() + p.begin * bytes;
      WEAVER_RETURN_IF_ERROR(run(k, b, p.end - p.begin));
    }
    return Status::Ok();
  }
  // The last leaf's key.  REQUIRES: a leaf.
  uint64_t last_key() const;
  // The pieces copied into keys, payloads and sides, for those who read
  // them whole (the carve).
  void flatten(size_t bytes);
  // Adds these leaves' figures to r (in Z-order, as the serial descent would).
  void add_to(ConstructResult* r) const;
};

// What the descent does with an octant: split it or keep it as a leaf.
// floor bounds the Vs at every point of the octant's closed box from below
// (so its descendants' too); vs, where it was sampled, is its least sample
// (else a negative number).  side is the octant's side of the ground: an
// octant wholly below (or above) it has its children there too, so only a
// cut octant's children are asked.  ceiling bounds the Vs of the box from
// above where the model's bounds were asked of it or of an ancestor (else
// HUGE_VAL): with the floor it may show every leaf below to be of one level.
struct Judgement {
  bool split = false;
  double floor = 0;
  double vs = -1;
  GroundSide side = GroundSide::kSolid;
  double ceiling = HUGE_VAL;
};

class Descent {
 public:
  static constexpr size_t kMaxPayloadBytes = 24;

  Descent(const ConstructOptions& o, const ConstructPlan& p, const VelocityModel& m)
      : o_(o),
        p_(p),
        model_(m),
        inv_rate_(1.0 / (o.freq * o.ppw)),
        has_q_(m.has_q()),
        blocks_(o.model_bounds && !p.carved),
        payload_bytes_((has_q_ ? 20 : 12) + (p.carved ? 4 : 0)) {
    for (int l = 0; l <= kMaxLevel; ++l) {
      edge_m_[l] = octant_edge(l) * p.tick_m;
      always_splits_[l] = l < o.min_level;
      may_split_[l] = l < o.max_level;
    }
  }

  // Whether the descent splits o (rather than writing it as a leaf).
  bool splits(const Octant& o) const { return judge(o).split; }
  // The same, with a lower bound on the Vs of o's box.
  Judgement judge(const Octant& o) const;
  // The judgement of each of o's children c with want[c] (all, for null),
  // given o's own (its floor bounds the Vs of o's box from below).
  void judge_children(const Octant& o, const Judgement& parent, const bool* want,
                      Judgement out[8]) const;
  // Whether the model's bounds over the closed box [lo, hi] (metres) keep
  // every octant of `level` inside it a leaf, as judge() would (false when
  // they do not settle it, or the model cannot say, or the ground decides).
  bool keeps_level_within(int level, const double lo[3], const double hi[3]) const;
  // The one level of all the leaves under o (split by j), where j's floor
  // and ceiling show it: each level above it splits at the ceiling, and it
  // is a leaf at the floor.  0 where they do not, or where the leaves would
  // be o's children alone (emit_siblings' case).
  int uniform_leaf_level(const Octant& o, const Judgement& j) const;
  // The leaves of o's subtree into *out; stops, with out->overflow, where
  // room does not allow another, or at once where a model read from
  // storage could not hold o's box in memory (where o splits).
  void visit_subtree(const Octant& o, LeafRoom& room, SubtreeLeaves* out) const;
  // A leaf's record: the material at o's centre (vp, vs, rho [, qp, qs] as
  // f32), payload_bytes() of them into out.
  void material(const Octant& o, std::byte* out) const;
  // The records of o's eight children, child c's at out + c *
  // payload_bytes(): material() of each, from one lattice of their centres.
  void children_materials(const Octant& o, std::byte* out) const;
  // material_schema's record, and the solid fraction where the ground is carved.
  size_t payload_bytes() const { return payload_bytes_; }
  const ConstructPlan& plan() const { return p_; }
  const VelocityModel& model() const { return model_; }

 private:
  enum class Settled { kLeaf, kSplit, kNo };
  // What the model's bounds over o's box say, and the floor they give.
  Settled settle(const Octant& o, double* floor, double* ceiling) const;
  Settled settled_by(const Octant& o, bool ok, float lo, float hi, double* floor,
                     double* ceiling) const;
  void settle_children(const Octant& o, const bool ask[8], Judgement out[8], bool open[8]) const;
  // o's closed box in metres, its corners as lattice() computes them.
  void box(const Octant& o, double lo[3], double hi[3]) const;
  // Vs at o's n x n x n lattice (n = 3: its 27 sample points).
  void lattice(const Octant& o, int n, float* out) const;
  double vs_min_of(const float* samples) const;
  // Splitting is monotone in vs: a lower vs never splits less.  Inline,
  // from tables by level: it is asked several times an octant.
  bool splits(const Octant& o, double vs) const { return level_splits(o.level, vs); }
  bool level_splits(int level, double vs) const {
    return always_splits_[level] || (edge_m_[level] > vs * inv_rate_ && may_split_[level]);
  }  // The first level from `from` on at which vs keeps an octant a leaf (or
  // kMaxLevel): the finest leaves under a floor of vs, the coarsest under a
  // ceiling of vs.
  int first_leaf_level(int from, double vs) const {
    int level = from;
    while (level < kMaxLevel && level_splits(level, vs)) ++level;
    return level;
  }

  // The leaves of `level` under o (uniform_leaf_level's), in Z-order, their
  // materials from lattices of 8 (or 4) centres a side; false where room
  // does not allow them.
  // REQUIRES: the subtree's least Vs of `level` is at most the floor of o's
  // judgement (so no leaf's samples could lower it).
  bool emit_block(const Octant& o, int level, LeafRoom& room, SubtreeLeaves* out) const;
  bool visit(const Octant& o, const Judgement& j, LeafRoom& room, SubtreeLeaves* out) const;
  // room.allows(n), out's vectors then reserved at the room it grants.
  bool room_for(LeafRoom& room, size_t n, SubtreeLeaves* out) const {
    if (!room.allows(n)) return false;
    out->fit(room.room(), payload_bytes_);
    return true;
  }
  // Focuses the model on subtree o's box and the margin its balance asks
  // for; o's judgement, and in *held whether the model holds the box.
  Judgement focus_on(const Octant& o, bool* held) const;
  // Where the ground decides: air is never split (but for --min-level), a
  // leaf it crosses is split down to --surface-edge.
  void apply_ground(const Octant& o, GroundSide side, Judgement* j) const;
  // judge() with o's side of the ground known (kSolid when not carved).
  Judgement judge_on(const Octant& o, GroundSide side) const;
  GroundSide ground_side(const Octant& o) const;
  bool emit_siblings(const Octant& o, const Judgement* children, LeafRoom& room,
                     SubtreeLeaves* out) const;
  // o's leaf (key: its key) into out, its payload in the room the caller
  // made for it; at_border false: o touches no side of the subtree
  // (out->root), whose borders then stand.
  void emit(const Octant& o, uint64_t key, const Judgement& j, const Material& m, bool at_border,
            SubtreeLeaves* out) const;
  // Whether o (inside root) touches a side of root.
  static bool touches_border(const Octant& o, const Octant& root);
  void add_figures(SubtreeLeaves* out) const;
  Material material_at_centre(const Octant& o) const;
  void child_materials(const Octant& o, Material* m) const;
  // The centres (metres) of n leaves of edge e (ticks) a side from the
  // corner start, each axis's as material_at_centre computes a leaf's: the
  // same integer tick times the tick's metres, plus half the edge.
  void leaf_centres(const uint32_t start[3], uint32_t e, int n, double centres[3][8]) const {
    const double t = p_.tick_m, half = e * t / 2;
    for (int a = 0; a < 3; ++a) {
      for (int i = 0; i < n; ++i) centres[a][i] = (start[a] + i * e) * t + half;
    }
  }
  static void note_border(const Octant& o, uint32_t e, SubtreeLeaves* out);
  // Field by field, each a fixed 4 bytes: one copy of a variable 12 or 20
  // bytes from an array just stored read across two stores, which the core
  // cannot forward, and stalled (6.6% of a one-thread construct).  Inline:
  // a block's leaves take one each.
  void to_payload(const Material& m, std::byte* out) const {
    std::memcpy(out, &m.vp, 4);
    std::memcpy(out + 4, &m.vs, 4);
    std::memcpy(out + 8, &m.rho, 4);
    size_t at = 12;
    if (has_q_) {
      std::memcpy(out + 12, &m.qp, 4);
      std::memcpy(out + 16, &m.qs, 4);
      at = 20;
    }
    // The solid fraction, last, is 1 until the carve (construct/carve.h) sets it.
    const float solid = 1.0f;
    if (p_.carved) std::memcpy(out + at, &solid, 4);
  }

  const ConstructOptions& o_;
  const ConstructPlan& p_;
  const VelocityModel& model_;
  double inv_rate_;
  bool has_q_;   // the model's, asked once (a virtual call a leaf was not free)
  bool blocks_;  // uniform_leaf_level may find blocks: bounds asked, no ground
  size_t payload_bytes_;
  std::array<double, kMaxLevel + 1> edge_m_;                   // a level's edge in metres
  std::array<bool, kMaxLevel + 1> always_splits_, may_split_;  // --min-level, --max-level
};

// The domain's subtrees in Z-order: the blocks, split down to task_level
// wherever the descent splits them.  The blocks are found by a walk down from
// the root, never all held at once (a domain of 999 x 999 x 374 blocks of
// 100 m has 373M of them).
class SubtreeList {
 public:
  // whole(o): an octant of the blocks' level or finer, above task_level,
  // that is a subtree as it is (null: none is).
  using Whole = std::function<bool(const Octant&)>;
  SubtreeList(const Descent& d, const ConstructPlan& p, int task_level, Whole whole = nullptr);
  // The next subtree; false after the last.
  bool next(Octant* o);

 private:
  // Whether o, at the blocks' level or above, holds a block of the domain.
  bool meets_domain(const Octant& o) const;

  const Descent& descent_;
  int block_level_, task_level_;
  Whole whole_;
  std::array<uint32_t, 3> domain_ticks_;  // the blocks' far sides
  std::vector<Octant> stack_;             // the next on top
};

}  // namespace weaver
