#include "export/shared_nodes.h"

namespace weaver {

Status SharedNodes::build(Mesh& mesh, const PartMap& parts, const std::string& scratch_dir,
                          uint64_t memory) {
  counts_.assign(parts.parts(), 0);
  if (mesh.node_count() >> kNodeBits) {
    return Status::InvalidArgument("more than 2^40 nodes: too many to share out by part");
  }
  ExternalSorter by_node(scratch_dir + "/by-node", memory / 2);
  ElementScan scan;
  WEAVER_RETURN_IF_ERROR(scan.start(mesh, 0, true));
  for (; scan.valid(); scan.next()) {
    uint32_t p = 0;
    WEAVER_RETURN_IF_ERROR(parts.part_of(scan.element().id, &p));
    for (uint64_t n : scan.element().nodes) WEAVER_RETURN_IF_ERROR(by_node.add({n, p}));
  }
  WEAVER_RETURN_IF_ERROR(scan.status());
  WEAVER_RETURN_IF_ERROR(by_node.finish());
  by_part_ = std::make_unique<ExternalSorter>(scratch_dir + "/by-part", memory / 2);
  std::vector<uint32_t> users;
  uint64_t node = UINT64_MAX;
  auto flush = [&]() -> Status {
    if (users.size() < 2) return Status::Ok();
    for (uint32_t q : users) {
      for (uint32_t r : users) {
        if (r == q) continue;
        WEAVER_RETURN_IF_ERROR(by_part_->add({(uint64_t{q} << kNodeBits) | node, r}));
        ++counts_[q];
      }
    }
    return Status::Ok();
  };
  for (;;) {
    KeyTag kt;
    bool done = false;
    WEAVER_RETURN_IF_ERROR(by_node.next(&kt, &done));
    if (done) break;
    if (kt.key != node) {
      WEAVER_RETURN_IF_ERROR(flush());
      node = kt.key;
      users.clear();
    }
    if (users.empty() || users.back() != kt.tag) users.push_back(uint32_t(kt.tag));
  }
  WEAVER_RETURN_IF_ERROR(flush());
  return by_part_->finish();
}

namespace {

// The Morton code of the first leaf of element id `id` (or 2^60 past the end).
Status anchor_morton(Mesh& mesh, uint64_t id, uint64_t* m) {
  *m = uint64_t{1} << (3 * kMaxLevel);
  if (id >= mesh.element_count()) return Status::Ok();
  uint64_t key = 0;
  WEAVER_RETURN_IF_ERROR(mesh.octants().select(id, &key, nullptr));
  *m = octant_key_morton(key);
  return Status::Ok();
}

}  // namespace

// The leaf holding pixel pm and its part (null if none): one of the last
// found, if it holds pm (the corners of neighbouring elements ask for the
// same few leaves), else from the octant table.
Status SharedNodes::leaf_at(Mesh& mesh, const PartMap& parts, uint64_t pm, const KnownLeaf** out) {
  *out = nullptr;
  for (const KnownLeaf& k : known_) {
    if (k.valid && ((k.morton ^ pm) >> k.span_bits) == 0) return *out = &k, Status::Ok();
  }
  uint64_t key = 0;
  bool hit = false;
  WEAVER_RETURN_IF_ERROR(mesh.octants().floor(pixel_key_of_morton(pm), &key, nullptr, &hit));
  const int span_bits = hit ? 3 * (kMaxLevel - octant_key_level(key)) : 0;
  if (!hit || ((octant_key_morton(key) ^ pm) >> span_bits) != 0) return Status::Ok();
  KnownLeaf& k = known_[next_known_++ % known_.size()];
  uint64_t id = 0;
  WEAVER_RETURN_IF_ERROR(mesh.octants().rank(key, &id));
  WEAVER_RETURN_IF_ERROR(parts.part_of(id, &k.part));
  k.valid = true;
  k.morton = octant_key_morton(key);
  k.span_bits = span_bits;
  k.octant = octant_from_key(key);
  *out = &k;
  return Status::Ok();
}

Status SharedNodes::other_parts_at(Mesh& mesh, const PartMap& parts, uint32_t part, Coord c,
                                   uint64_t run_lo, uint64_t run_hi,
                                   std::vector<uint32_t>* others) {
  const uint32_t at[3] = {c.x, c.y, c.z};
  for (int d = 0; d < 8; ++d) {
    uint32_t q[3];  // the pixel on d's side of c (bit a: the + side on axis a)
    bool inside = true;
    for (int a = 0; a < 3; ++a) {
      const bool plus = (d >> a) & 1;
      inside = inside && (plus ? at[a] < kRootEdge : at[a] > 0);
      q[a] = plus ? at[a] : at[a] - 1;
    }
    if (!inside) continue;
    const uint64_t pm = octant_morton({q[0], q[1], q[2], kMaxLevel});
    if (pm >= run_lo && pm < run_hi) continue;  // in a leaf of the part, or none
    const KnownLeaf* leaf = nullptr;
    WEAVER_RETURN_IF_ERROR(leaf_at(mesh, parts, pm, &leaf));
    if (leaf == nullptr) continue;
    const Octant& o = leaf->octant;
    const uint32_t e = octant_edge(o), lo[3] = {o.x, o.y, o.z};
    bool corner = true;  // c is a corner of the leaf (which holds q)
    for (int a = 0; a < 3; ++a) corner = corner && (at[a] == lo[a] || at[a] == lo[a] + e);
    if (corner && leaf->part != part) others->push_back(leaf->part);
  }
  return Status::Ok();
}

Status SharedNodes::build_part(Mesh& mesh, const PartMap& parts, const Selection& part,
                               const std::string& scratch_dir, uint64_t memory) {
  counts_.assign(parts.parts(), 0);
  if (mesh.node_count() >> kNodeBits) {
    return Status::InvalidArgument("more than 2^40 nodes: too many to share out by part");
  }
  // Lookups are skipped for pixels in the run's own leaves, when it is one.
  uint64_t run_lo = 0, run_hi = 0;
  if (part.parts == nullptr) {
    WEAVER_RETURN_IF_ERROR(anchor_morton(mesh, part.first, &run_lo));
    WEAVER_RETURN_IF_ERROR(anchor_morton(mesh, part.end, &run_hi));
  }
  ExternalSorter pairs(scratch_dir + "/pairs", memory / 2);
  std::vector<uint32_t> others;
  WEAVER_RETURN_IF_ERROR(scan_selected(mesh, part, true, [&](MeshElement& el) {
    const uint32_t e = octant_edge(el.octant);
    for (int k = 0; k < 8; ++k) {
      const Coord c{el.octant.x + (k & 1 ? e : 0), el.octant.y + (k & 2 ? e : 0),
                    el.octant.z + (k & 4 ? e : 0)};
      others.clear();
      WEAVER_RETURN_IF_ERROR(other_parts_at(mesh, parts, part.part, c, run_lo, run_hi, &others));
      for (uint32_t q : others) WEAVER_RETURN_IF_ERROR(pairs.add({el.nodes[k], q}));
    }
    return Status::Ok();
  }));
  WEAVER_RETURN_IF_ERROR(pairs.finish());
  by_part_ = std::make_unique<ExternalSorter>(scratch_dir + "/by-part", memory / 2);
  KeyTag last{UINT64_MAX, 0};
  for (;;) {
    KeyTag kt;
    bool done = false;
    WEAVER_RETURN_IF_ERROR(pairs.next(&kt, &done));
    if (done) break;
    if (kt.key == last.key && kt.tag == last.tag) continue;
    last = kt;
    WEAVER_RETURN_IF_ERROR(by_part_->add({(uint64_t{part.part} << kNodeBits) | kt.key, kt.tag}));
    ++counts_[part.part];
  }
  return by_part_->finish();
}

Status SharedNodes::next(uint32_t p, uint64_t* node, uint32_t* other) {
  KeyTag kt;
  bool done = false;
  WEAVER_RETURN_IF_ERROR(by_part_->next(&kt, &done));
  if (done || (kt.key >> kNodeBits) != p) {
    return Status::Internal("shared nodes of part " + std::to_string(p) + " read out of order");
  }
  *node = kt.key & ((uint64_t{1} << kNodeBits) - 1);
  *other = uint32_t(kt.tag);
  return Status::Ok();
}

}  // namespace weaver
