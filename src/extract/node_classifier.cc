#include "extract/node_classifier.h"

#include <algorithm>

namespace weaver {
namespace {

// The pixel next to node n in direction d (bit a set: the + side on axis a).
// False if it lies outside the root.
bool direction_pixel(Coord n, int d, Coord* p) {
  const uint32_t c[3] = {n.x, n.y, n.z};
  uint32_t q[3];
  for (int a = 0; a < 3; ++a) {
    if ((d >> a) & 1) {
      if (c[a] >= kRootEdge) return false;
      q[a] = c[a];
    } else {
      if (c[a] == 0) return false;
      q[a] = c[a] - 1;
    }
  }
  *p = {q[0], q[1], q[2]};
  return true;
}

}  // namespace

// The leaf holding pixel p, if any: the active bucket's leaves first, then
// the octant table (pixels in earlier buckets, and leaves larger than a bucket).
Status NodeClassifier::leaf_at(Coord p, Octant* leaf, bool* found) {
  const uint64_t pk = pixel_key(p);
  *found = false;
  const uint64_t pm = node_key(p);
  if (leaf_keys_ != nullptr && pm >= local_start_ && pm < local_end_) {
    auto it = std::upper_bound(leaf_keys_->begin(), leaf_keys_->end(), pk);
    if (it != leaf_keys_->begin() && octant_contains_point(octant_from_key(*(it - 1)), p)) {
      *leaf = octant_from_key(*(it - 1));
      *found = true;
    }
    return Status::Ok();
  }
  uint64_t key = 0;
  bool hit = false;
  WEAVER_RETURN_IF_ERROR(octants_.floor(pk, &key, nullptr, &hit));
  if (hit && octant_contains_point(octant_from_key(key), p)) {
    *leaf = octant_from_key(key);
    *found = true;
  }
  return Status::Ok();
}

Status NodeClassifier::classify(uint64_t key, uint8_t mask, NodeKind* kind) {
  *kind = NodeKind::kAnchored;
  if (mask == 0xFF) return Status::Ok();
  const Coord n = morton_decode(key);
  uint8_t settled = mask;
  for (int d = 0; d < 8; ++d) {
    if ((settled >> d) & 1) continue;
    Coord p;
    Octant leaf;
    bool found = false;
    if (direction_pixel(n, d, &p)) WEAVER_RETURN_IF_ERROR(leaf_at(p, &leaf, &found));
    if (!found) {  // outside the root or the domain
      settled |= static_cast<uint8_t>(1u << d);
      continue;
    }
    NodeKind here = NodeKind::kAnchored;
    WEAVER_RETURN_IF_ERROR(kind_on(n, leaf, mask, &here));
    if (*kind != NodeKind::kAnchored && here != *kind) return unbalanced(n, leaf, mask);
    *kind = here;
    for (int d2 = 0; d2 < 8; ++d2) {  // every cell this leaf covers is settled
      Coord p2;
      if (direction_pixel(n, d2, &p2) && octant_contains_point(leaf, p2)) {
        settled |= static_cast<uint8_t>(1u << d2);
      }
    }
  }
  return Status::Ok();
}

// Node n lies on the closure of `leaf` but is not its corner.
Status NodeClassifier::kind_on(Coord n, const Octant& leaf, uint8_t mask, NodeKind* kind) {
  const uint32_t e = octant_edge(leaf), half = e / 2;
  const uint32_t c[3] = {n.x, n.y, n.z}, lo[3] = {leaf.x, leaf.y, leaf.z};
  int inside = 0;
  for (int a = 0; a < 3; ++a) {
    if (c[a] > lo[a] && c[a] < lo[a] + e) {
      if (c[a] - lo[a] != half) return unbalanced(n, leaf, mask);
      ++inside;
    }
  }
  if (inside == 0 || inside == 3) {
    return Status::Corruption("node (" + std::to_string(n.x) + " " + std::to_string(n.y) + " " +
                              std::to_string(n.z) + ") is inconsistent with leaf " +
                              describe_octant(leaf) + ": overlapping octants?");
  }
  *kind = inside == 1 ? NodeKind::kEdge : NodeKind::kFace;
  return Status::Ok();
}

// Names the coarse leaf and a finer element that has n as a corner.
Status NodeClassifier::unbalanced(Coord n, const Octant& coarse, uint8_t mask) {
  std::string fine = "?";
  for (int d = 0; d < 8; ++d) {
    Coord p;
    Octant leaf;
    bool found = false;
    if (!((mask >> d) & 1) || !direction_pixel(n, d, &p)) continue;
    WEAVER_RETURN_IF_ERROR(leaf_at(p, &leaf, &found));
    if (found) {
      fine = describe_octant(leaf);
      break;
    }
  }
  return Status::InvalidArgument("the octree is not 2:1 balanced: octant " +
                                 describe_octant(coarse) + " and octant " + fine +
                                 " are face or edge neighbours more than one level apart");
}

}  // namespace weaver
