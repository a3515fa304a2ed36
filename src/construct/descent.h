// Construct's descent over one subtree, and the subtrees that cut the domain
// into tasks for worker threads.
//
// A subtree is visited depth first in Z-order: an octant whose least Vs over
// its 27 sample points (the corners, edge midpoints, face centres and centre)
// asks for a finer edge (or that lies above --min-level) is split, any other
// is a leaf, written with the material at its centre.  A split octant's
// 5 x 5 x 5 lattice holds its children's sample points, so each is
// evaluated once.  Subtrees are independent, so workers may visit them in any
// order; their leaves are written in Z-order (construct.cc), and the table
// is the same for any number of threads.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "construct/construct.h"
#include "model/velocity_model.h"
#include "schema/octant.h"

namespace weaver {

// The leaves of one subtree, in key order, and what construct reports of them.
struct SubtreeLeaves {
  std::vector<uint64_t> keys;
  std::vector<std::byte> payloads;  // vp, vs, rho [, qp, qs] as f32 (material_schema)
  LevelCounts levels{};
  uint64_t elements = 0;
  double smallest_edge_m = 0, largest_edge_m = 0, worst_ppw = 0;
  bool overflow = false;  // more leaves than the cap: visit the children instead

  void clear();
  // Adds these leaves' figures to r (in Z-order, as the serial descent would).
  void add_to(ConstructResult* r) const;
};

class Descent {
 public:
  static constexpr size_t kMaxPayloadBytes = 20;

  Descent(const ConstructOptions& o, const ConstructPlan& p, const VelocityModel& m)
      : o_(o), p_(p), model_(m), inv_rate_(1.0 / (o.freq * o.ppw)) {}

  // Whether the descent splits o (rather than writing it as a leaf).
  bool splits(const Octant& o) const;
  // The same from o's 27 samples (sample_points, or children_samples of
  // its parent), as the descent decides it.
  bool splits_sampled(const Octant& o, const float* samples) const {
    return splits(o, vs_min_of(samples));
  }
  // Vs at o's 27 sample points (corners, edge midpoints, face centres, centre).
  void sample_points(const Octant& o, float* out) const { lattice(o, 3, out); }
  // The 27 samples of each of o's children, from o's 5 x 5 x 5 lattice.
  void children_samples(const Octant& o, float (*out)[27]) const;
  // The leaves of o's subtree into *out; stops, with out->overflow, past cap.
  void visit_subtree(const Octant& o, size_t cap, SubtreeLeaves* out) const;
  // A leaf's record: the material at o's centre (vp, vs, rho [, qp, qs] as
  // f32), payload_bytes() of them into out.
  void material(const Octant& o, std::byte* out) const;
  size_t payload_bytes() const { return model_.has_q() ? 20 : 12; }  // material_schema's record
  const ConstructPlan& plan() const { return p_; }
  const VelocityModel& model() const { return model_; }

 private:
  // Vs at o's n x n x n lattice (n = 3: its 27 sample points).
  void lattice(const Octant& o, int n, float* out) const;
  double vs_min_of(const float* samples) const;
  bool splits(const Octant& o, double vs) const;
  bool visit(const Octant& o, const float* samples, size_t cap, SubtreeLeaves* out) const;
  void emit(const Octant& o, double edge_m, double vs, SubtreeLeaves* out) const;

  const ConstructOptions& o_;
  const ConstructPlan& p_;
  const VelocityModel& model_;
  double inv_rate_;
};

// The domain's subtrees in Z-order: the blocks, split down to task_level
// wherever the descent splits them.
class SubtreeList {
 public:
  SubtreeList(const Descent& d, const ConstructPlan& p, int task_level);
  // The next subtree; false after the last.
  bool next(Octant* o);

 private:
  const Descent& descent_;
  int task_level_;
  std::vector<Octant> stack_;  // the next on top
};

}  // namespace weaver
