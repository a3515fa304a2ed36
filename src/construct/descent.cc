#include "construct/descent.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "construct/carve.h"

namespace weaver {

// Point i of an n-point lattice axis (n = 3 or 5) over an octant starting
// at tick a with edge e sits at a + i e / (n - 1) ticks: a whole number of
// quarter ticks, so every octant that shares the point computes the same
// coordinate, rounded once.
void Descent::lattice(const Octant& o, int n, float* out) const {
  const double quarter = p_.tick_m / 4;
  const uint64_t step = 4 * uint64_t{octant_edge(o)} / (n - 1);
  double axes[3][5];
  const uint32_t start[3] = {o.x, o.y, o.z};
  for (int a = 0; a < 3; ++a)
    for (int i = 0; i < n; ++i) axes[a][i] = double(4 * uint64_t{start[a]} + i * step) * quarter;
  model_.vs_on_lattice(axes[0], axes[1], axes[2], n, out);
}

// The first and last points of every lattice of o, so the box holds them.
void Descent::box(const Octant& o, double lo[3], double hi[3]) const {
  const double quarter = p_.tick_m / 4;
  const uint64_t e4 = 4 * uint64_t{octant_edge(o)};
  const uint32_t start[3] = {o.x, o.y, o.z};
  for (int a = 0; a < 3; ++a) {
    lo[a] = double(4 * uint64_t{start[a]}) * quarter;
    hi[a] = double(4 * uint64_t{start[a]} + e4) * quarter;
  }
}

// The least Vs over the 27 sample points, floored by --vs-min.
// Four running minima, not std::min_element's one: 27 dependent compares
// were a fifth of construct.  (The minimum is the same in any order.)
double Descent::vs_min_of(const float* samples) const {
  float m[4] = {samples[0], samples[1], samples[2], samples[3]};
  for (int i = 4; i < 24; i += 4) {
    for (int k = 0; k < 4; ++k) m[k] = std::min(m[k], samples[i + k]);
  }
  for (int i = 24; i < 27; ++i) m[0] = std::min(m[0], samples[i]);
  return std::max<double>(std::min(std::min(m[0], m[1]), std::min(m[2], m[3])), o_.vs_min);
}

// The samples lie in o's box, so their least Vs lies within the bounds: if
// the lower bound keeps o a leaf, so does the least sample; if the upper
// bound splits it, so does the least sample.
Descent::Settled Descent::settle(const Octant& o, double* floor, double* ceiling) const {
  if (!o_.model_bounds) return Settled::kNo;
  float lo, hi;
  double box_lo[3], box_hi[3];
  box(o, box_lo, box_hi);
  const bool ok = model_.vs_bounds(box_lo, box_hi, &lo, &hi);  // before lo and hi are read
  return settled_by(o, ok, lo, hi, floor, ceiling);
}

// What bounds [lo, hi] on the Vs of o's box say (ok false: the model gave
// none), and the floor they give; the ceiling is lowered to hi's.
Descent::Settled Descent::settled_by(const Octant& o, bool ok, float lo, float hi, double* floor,
                                     double* ceiling) const {
  if (!ok) return Settled::kNo;
  *floor = std::max<double>(lo, o_.vs_min);
  *ceiling = std::min(*ceiling, std::max<double>(hi, o_.vs_min));
  if (!splits(o, *floor)) return Settled::kLeaf;
  if (splits(o, std::max<double>(hi, o_.vs_min))) return Settled::kSplit;
  return Settled::kNo;
}

// settle() for the children c of o with ask[c], their bounds asked of the
// model at once (their boxes share work); open[c] where they do not
// settle it.  Each box's sides as box() computes the child's.
void Descent::settle_children(const Octant& o, const bool ask[8], Judgement out[8],
                              bool open[8]) const {
  if (!o_.model_bounds) {
    for (int c = 0; c < 8; ++c) open[c] = ask[c];
    return;
  }
  const double quarter = p_.tick_m / 4;
  const uint64_t e4 = 4 * uint64_t{octant_edge(o)};
  const uint32_t start[3] = {o.x, o.y, o.z};
  double edges[3][3];
  for (int a = 0; a < 3; ++a) {
    const uint64_t base = 4 * uint64_t{start[a]};
    edges[a][0] = double(base) * quarter;
    edges[a][1] = double(base + e4 / 2) * quarter;
    edges[a][2] = double(base + e4) * quarter;
  }
  float lo[8], hi[8];
  bool ok[8] = {};
  model_.vs_bounds_of_eighths(edges, ask, lo, hi, ok);
  for (int c = 0; c < 8; ++c) {
    if (!ask[c]) continue;
    Judgement& j = out[c];
    const double parent_floor = j.floor;
    const Settled s = settled_by(octant_child(o, c), ok[c], lo[c], hi[c], &j.floor, &j.ceiling);
    j.floor = std::max(j.floor, parent_floor);
    open[c] = s == Settled::kNo;
    j.split = s == Settled::kSplit;
  }
}

// An octant of `level` in the box has its samples there, so their least
// Vs is at least the bound's: if that keeps it a leaf, so do they (settle's
// argument).  A carved plan's cut octants split by --surface-edge too.
bool Descent::keeps_level_within(int level, const double lo[3], const double hi[3]) const {
  if (!o_.model_bounds || p_.carved) return false;
  float vs_lo, vs_hi;
  if (!model_.vs_bounds(lo, hi, &vs_lo, &vs_hi)) return false;
  const Octant o{0, 0, 0, static_cast<uint8_t>(level)};
  return !splits(o, std::max<double>(vs_lo, o_.vs_min));
}

Judgement Descent::judge(const Octant& o) const {
  return judge_on(o, p_.carved ? ground_side(o) : GroundSide::kSolid);
}

Judgement Descent::judge_on(const Octant& o, GroundSide side) const {
  Judgement j;
  j.floor = o_.vs_min;
  j.side = side;
  if (side == GroundSide::kAir) {
    apply_ground(o, side, &j);
    return j;
  }
  const Settled s = settle(o, &j.floor, &j.ceiling);
  if (s != Settled::kNo) {
    j.split = s == Settled::kSplit;
  } else {
    float samples[27];
    lattice(o, 3, samples);
    j.vs = vs_min_of(samples);
    j.split = splits(o, j.vs);
  }
  apply_ground(o, side, &j);
  return j;
}

GroundSide Descent::ground_side(const Octant& o) const {
  double lo[3], hi[3];
  box(o, lo, hi);
  return side_of_ground(p_.ground, lo, hi);
}

void Descent::apply_ground(const Octant& o, GroundSide side, Judgement* j) const {
  switch (side) {
    case GroundSide::kAir:
      // Nothing of it is meshed: no samples, no split but --min-level's.
      j->split = o.level < o_.min_level;
      j->floor = HUGE_VAL;
      j->vs = -1;
      return;
    case GroundSide::kCut:
      if (o_.surface_edge_m > 0 && octant_edge(o) * p_.tick_m > o_.surface_edge_m &&
          o.level < o_.max_level)
        j->split = true;
      return;
    case GroundSide::kSolid: return;
  }
}

// Children that their parent's floor keeps leaves cost nothing; the others
// ask the model's bounds; those the bounds leave open are sampled, from the
// parent's 5 x 5 x 5 lattice when at least kSharedLattice of them are
// (three: one call for 125 points, not three for 81, was 0.986x the 2 Hz
// construct's time, twice, where two was no faster again).  Not
// for some children only (a subtree's balance, judging the octants around
// the subtree): the parent's lattice reaches into the children not asked,
// further from the model's focus, where a model database answers each point
// by a search of its table (0.95x the time of a construct from one).
void Descent::judge_children(const Octant& o, const Judgement& parent, const bool* want,
                             Judgement out[8]) const {
  const double floor = parent.floor;
  const int kSharedLattice = want == nullptr ? 3 : 9;
  bool ask[8] = {}, open[8] = {};
  bool asked = false;
  for (int c = 0; c < 8; ++c) {
    if (want != nullptr && !want[c]) continue;
    const Octant child = octant_child(o, c);
    Judgement& j = out[c];
    j = Judgement{false, floor, -1, GroundSide::kSolid, parent.ceiling};
    if (p_.carved) {
      const GroundSide side = parent.side == GroundSide::kCut ? ground_side(child) : parent.side;
      if (side != GroundSide::kSolid) {
        j = judge_on(child, side);
        continue;
      }
    }
    ask[c] = splits(child, floor);
    asked |= ask[c];
  }
  if (!asked) return;
  settle_children(o, ask, out, open);
  int opened = 0;
  for (int c = 0; c < 8; ++c) opened += open[c];
  if (opened == 0) return;
  float fine[125];
  if (opened >= kSharedLattice) lattice(o, 5, fine);
  for (int c = 0; c < 8; ++c) {
    if (!open[c]) continue;
    float samples[27];
    if (opened >= kSharedLattice) {
      const int cx = 2 * (c & 1), cy = (c & 2), cz = (c & 4) / 2;
      for (int k = 0; k < 3; ++k)
        for (int j = 0; j < 3; ++j)
          for (int i = 0; i < 3; ++i)
            samples[(k * 3 + j) * 3 + i] = fine[((cz + k) * 5 + cy + j) * 5 + cx + i];
    } else {
      lattice(octant_child(o, c), 3, samples);
    }
    out[c].vs = vs_min_of(samples);
    out[c].split = splits(octant_child(o, c), out[c].vs);
  }
}

void Descent::visit_subtree(const Octant& o, LeafRoom& room, SubtreeLeaves* out) const {
  out->clear();
  out->root = o;
  bool held = true;
  const Judgement j = focus_on(o, &held);
  // Where a model read from storage could not hold the subtree's box in
  // memory, each of its points would be searched for in storage (at 1 Hz
  // from the 100 m model database, 4x the time): its eight children are
  // visited instead, as for a subtree past its room, each box an eighth.
  // Only where o splits: a leaf's children are no subtrees of the octree.
  if (!held && j.split) {
    out->overflow = true;
    return;
  }
  out->overflow = !visit(o, j, room, out);
  if (!out->overflow) add_figures(out);
}

// The balance around the subtree (subtree_balance.h) asks for its box grown
// by its largest leaf at each side, whether it stands for that box grown by
// half the coarsest leaf's edge more, and descends again the octants that
// meet the grown box (each up to the coarsest leaf's size past it): a model
// database's region that holds them all answers them without its table,
// and is not loaded again.  An eighth of the edge more held it wherever
// those leaves are no larger (construct from the 100 m model database:
// 0.89x the time at 0.5 Hz on one thread, 0.85x at 1 Hz on two; a
// sixteenth was 0.85x and 0.92x); now the margin is twice the coarsest leaf
// the ceiling of o's bounds allows (and two ticks, for rounding) where that
// is less than the eighth: where the subtrees are large against their
// leaves (the region read 1.8x the model at 0.5 Hz).  It is asked first as the
// thread's last subtree needed (its neighbour's material is alike), then
// again, larger, where o needs more.  Analytic models ignore the focus.
Judgement Descent::focus_on(const Octant& o, bool* held) const {
  if (!model_.loads_focus()) return judge(o);  // focus() would do nothing
  double lo[3], hi[3];
  box(o, lo, hi);
  const double edge = hi[0] - lo[0];
  thread_local double last_share = 1.0 / 8;  // the last margin, as a share of its subtree's edge
  auto focus = [&](double margin) {
    const double l[3] = {lo[0] - margin, lo[1] - margin, lo[2] - margin};
    const double h[3] = {hi[0] + margin, hi[1] + margin, hi[2] + margin};
    *held = model_.focus(l, h);
  };
  const double guess = last_share * edge;
  focus(guess);
  const Judgement j = judge(o);
  double need = edge / 8;  // no ceiling: as before
  if (j.ceiling < HUGE_VAL) {
    const int level = first_leaf_level(o.level, j.ceiling);
    // Never more than the eighth: where the leaves are coarser, the
    // balance loads its own box (a region of many times the subtree's
    // side could pass the region's room and be dropped after loading).
    need = std::min(need, 2 * edge_m_[level] + 2 * p_.tick_m);
  }
  if (need > guess) focus(need);
  last_share = need / edge;
  return j;
}

// False once room does not allow another leaf.
bool Descent::visit(const Octant& o, const Judgement& j, LeafRoom& room, SubtreeLeaves* out) const {
  if (j.split) {
    // A block of one level whose floor cannot lower the level's least Vs
    // is written whole; otherwise its leaves are judged one by one.
    const int level = uniform_leaf_level(o, j);
    if (level > 0 && out->least_vs[level] <= j.floor) return emit_block(o, level, room, out);
    Judgement children[8];
    judge_children(o, j, nullptr, children);
    bool leaves = true;
    for (const Judgement& c : children) leaves = leaves && !c.split;
    if (leaves) return emit_siblings(o, children, room, out);
    for (int c = 0; c < 8; ++c) {
      if (!visit(octant_child(o, c), children[c], room, out)) return false;
    }
    return true;
  }
  if (!room_for(room, out->elements + 1, out)) return false;
  out->payloads.resize(out->payloads.size() + payload_bytes_);
  emit(o, octant_key(o), j, material_at_centre(o), true, out);
  return true;
}

// Every octant below o has its samples in o's box, between j's floor and
// ceiling.  If each level from o's children's to `level - 1` splits at
// the ceiling, the descent splits every octant there whatever it finds
// (splitting is monotone in Vs); if `level` is a leaf at the floor, every
// octant there is a leaf: none is ever sampled, and its floor, at least
// j's, is all emit() would look at.
int Descent::uniform_leaf_level(const Octant& o, const Judgement& j) const {
  if (!blocks_ || j.ceiling == HUGE_VAL) return 0;
  const int level = first_leaf_level(o.level + 1, j.floor);
  if (level < o.level + 2 || level >= kMaxLevel || level_splits(level, j.floor)) return 0;
  return level_splits(level - 1, j.ceiling) ? level : 0;
}

SubtreeList::SubtreeList(const Descent& d, const ConstructPlan& p, int task_level, Whole whole)
    : descent_(d), block_level_(p.block_level), task_level_(task_level), whole_(std::move(whole)) {
  const uint32_t e = octant_edge(p.block_level);
  for (int a = 0; a < 3; ++a) domain_ticks_[a] = p.blocks[a] * e;
  stack_.push_back({0, 0, 0, 0});
}

bool SubtreeList::meets_domain(const Octant& o) const {
  return o.x < domain_ticks_[0] && o.y < domain_ticks_[1] && o.z < domain_ticks_[2];
}

bool SubtreeList::next(Octant* o) {
  while (!stack_.empty()) {
    const Octant top = stack_.back();
    stack_.pop_back();
    if (top.level <= block_level_ && !meets_domain(top)) continue;
    if (top.level >= block_level_ &&
        (top.level >= task_level_ || (whole_ && whole_(top)) || !descent_.splits(top))) {
      *o = top;
      return true;
    }
    for (int c = 7; c >= 0; --c) stack_.push_back(octant_child(top, c));  // child 0 on top
  }
  return false;
}

}  // namespace weaver
