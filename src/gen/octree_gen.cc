#include "gen/octree_gen.h"

#include <algorithm>
#include <cmath>
#include <random>

namespace weaver {
namespace {

Status domain_blocks(const GenOptions& o, std::vector<Octant>* out) {
  if (o.block_level < 0 || o.block_level > kMaxLevel) {
    return Status::InvalidArgument("block level must be in [0, 20]");
  }
  const uint64_t per_axis = uint64_t{1} << o.block_level;
  for (int a = 0; a < 3; ++a) {
    if (o.blocks[a] == 0 || o.blocks[a] > per_axis) {
      return Status::InvalidArgument("blocks per axis must be in [1, " + std::to_string(per_axis) +
                                     "] at block level " + std::to_string(o.block_level));
    }
  }
  const uint32_t e = octant_edge(o.block_level);
  for (uint32_t k = 0; k < o.blocks[2]; ++k)
    for (uint32_t j = 0; j < o.blocks[1]; ++j)
      for (uint32_t i = 0; i < o.blocks[0]; ++i) {
        out->push_back({i * e, j * e, k * e, static_cast<uint8_t>(o.block_level)});
      }
  return Status::Ok();
}

void refine_uniform(const Octant& o, int level, std::vector<Octant>* out) {
  if (o.level == level) {
    out->push_back(o);
    return;
  }
  for (int k = 0; k < 8; ++k) refine_uniform(octant_child(o, k), level, out);
}

double distance_to_sphere(const Octant& o, double radius) {
  const double c = kRootEdge / 2.0, e = octant_edge(o);
  const double lo[3] = {double(o.x), double(o.y), double(o.z)};
  double near = 0, far = 0;
  for (int a = 0; a < 3; ++a) {
    const double dn = std::max({lo[a] - c, c - (lo[a] + e), 0.0});
    const double df = std::max(std::abs(lo[a] - c), std::abs(lo[a] + e - c));
    near += dn * dn;
    far += df * df;
  }
  // The box spans distances [sqrt(near), sqrt(far)] from the centre.
  const double r = radius * kRootEdge;
  if (r < std::sqrt(near)) return std::sqrt(near) - r;
  if (r > std::sqrt(far)) return r - std::sqrt(far);
  return 0;
}

// Depth-first in child order, so leaves come out in key order.
void refine_sphere(const Octant& o, const GenOptions& g, std::vector<Octant>* out) {
  const bool refine = o.level < g.level || (o.level < g.max_level &&
                                            distance_to_sphere(o, g.radius) < 2.0 * octant_edge(o));
  if (!refine) {
    out->push_back(o);
    return;
  }
  for (int k = 0; k < 8; ++k) refine_sphere(octant_child(o, k), g, out);
}

struct Point3 {
  double x, y, z;
};

double distance_to_point(const Octant& o, const Point3& p) {
  const double e = octant_edge(o);
  const double dx = std::max({double(o.x) - p.x, p.x - (double(o.x) + e), 0.0});
  const double dy = std::max({double(o.y) - p.y, p.y - (double(o.y) + e), 0.0});
  const double dz = std::max({double(o.z) - p.z, p.z - (double(o.z) + e), 0.0});
  return std::sqrt(dx * dx + dy * dy + dz * dz);
}

// Refines o if some point lies within 2 edges of it.  Only those points can
// matter to its children (closer boxes, smaller thresholds), so only they go down.
void refine_points(const Octant& o, const GenOptions& g, const std::vector<Point3>& near,
                   std::vector<Octant>* out) {
  std::vector<Point3> closer;
  for (const Point3& p : near) {
    if (distance_to_point(o, p) < 2.0 * octant_edge(o)) closer.push_back(p);
  }
  const bool refine = o.level < g.level || (o.level < g.max_level && !closer.empty());
  if (!refine) {
    out->push_back(o);
    return;
  }
  for (int k = 0; k < 8; ++k) refine_points(octant_child(o, k), g, closer, out);
}

}  // namespace

Status generate_octree(const GenOptions& o, std::vector<Octant>* leaves) {
  std::vector<Octant> blocks;
  WEAVER_RETURN_IF_ERROR(domain_blocks(o, &blocks));
  leaves->clear();
  std::mt19937_64 rng(o.seed);
  if (o.kind == GenOptions::Kind::kUniform) {
    if (o.level < o.block_level || o.level > kMaxLevel) {
      return Status::InvalidArgument("uniform level must be in [block level, 20]");
    }
    const uint64_t count = blocks.size() << (3 * (o.level - o.block_level));
    if (count > (uint64_t{1} << 31)) return Status::InvalidArgument("too many leaves to generate");
    for (const Octant& b : blocks) refine_uniform(b, o.level, leaves);
  } else if (o.kind == GenOptions::Kind::kSphere) {
    if (o.max_level < o.level || o.max_level > kMaxLevel || !(o.radius > 0)) {
      return Status::InvalidArgument("sphere needs level <= max level <= 20 and a radius > 0");
    }
    for (const Octant& b : blocks) refine_sphere(b, o, leaves);
  } else if (o.kind == GenOptions::Kind::kPoints) {
    if (o.max_level < o.level || o.max_level > kMaxLevel) {
      return Status::InvalidArgument("points needs level <= max level <= 20");
    }
    std::uniform_real_distribution<double> coord(0.0, double(kRootEdge));
    std::vector<Point3> points(o.points);
    for (Point3& p : points) p = {coord(rng), coord(rng), coord(rng)};
    for (const Octant& b : blocks) refine_points(b, o, points, leaves);
  } else {
    if (o.max_level <= o.block_level) {
      return Status::InvalidArgument("max level must exceed the block level");
    }
    // Split random leaves until there are enough; a leaf at max_level stays.
    *leaves = blocks;
    uint64_t stuck = 0;
    while (leaves->size() < o.leaves && stuck < 1000) {
      const size_t i = rng() % leaves->size();
      const Octant leaf = (*leaves)[i];
      if (leaf.level >= o.max_level) {
        ++stuck;
        continue;
      }
      stuck = 0;
      (*leaves)[i] = octant_child(leaf, 0);
      for (int k = 1; k < 8; ++k) leaves->push_back(octant_child(leaf, k));
    }
  }
  if (o.shuffle) {
    std::shuffle(leaves->begin(), leaves->end(), rng);
  } else {
    std::sort(leaves->begin(), leaves->end(),
              [](const Octant& a, const Octant& b) { return octant_key(a) < octant_key(b); });
  }
  return Status::Ok();
}

}  // namespace weaver
