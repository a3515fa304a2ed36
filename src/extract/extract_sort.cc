// Two-level bucket sort (paper, section 4), generalised to 3D, to non-cube
// domains and to any bucket size.
//
// High-level buckets are aligned octants of one level, processed in Z-order.
// The leaves of the active bucket are its low-level buckets.  Each leaf
// contributes its 8 corners as nodal pixels, tagged with the direction (one
// of the 8 cells around the node) in which the leaf lies; a pixel that falls
// into a later bucket (the active bucket's far faces) is spilled and picked
// up when that bucket becomes active.  Duplicates merge in a hash table by
// ORing direction bits.
//
// Dangling or anchored: a node whose 8 cells all hold an element having it as
// a corner is anchored.  Otherwise each empty cell is settled by an aggregate
// hit on its pixel: no leaf there means outside the domain; a leaf that does
// not have the node as a corner has it on an edge (one axis strictly inside
// the leaf) or a face (two axes) -- the node dangles.  Direction counts and
// levels alone cannot tell a dangling node from one on a re-entrant corner of
// a non-cube domain; the hit can.  A node on a leaf's edge or face but not at
// its midpoint or centre proves the octree is not 2:1 balanced.
#include <algorithm>
#include <unistd.h>

#include "db/database.h"
#include "db/node_table.h"
#include "db/octant_table.h"
#include "extract/extract.h"
#include "extract/node_hash.h"
#include "extract/spill_store.h"
#include "schema/node.h"
#include "schema/octant.h"

namespace weaver {
namespace {

// Bytes of memory per finest-level leaf in the active bucket: its key, about
// one node in a half-full hash table (9 bytes / 0.5), and the sort vector.
constexpr uint64_t kBytesPerLeaf = 8 + 24 + 16;
// No bucket holds more than 8^kMaxBucketDepth finest leaves whatever the
// budget: its hash table then stays in the CPU caches.  Larger buckets only
// save spills, which cost far less than cache misses on every corner.
constexpr int kMaxBucketDepth = 6;

std::string describe(const Octant& o) {
  return "(" + std::to_string(o.x) + " " + std::to_string(o.y) + " " + std::to_string(o.z) + " " +
         std::to_string(o.level) + ")";
}

struct Bucketing {
  int level;  // bucket level: edge 2^(20-level)
  int shift;  // bits of a node key below the bucket id
  uint64_t of_key(uint64_t node_key) const { return node_key >> shift; }
};

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

class BucketExtractor {
 public:
  BucketExtractor(BTree& octants, BTree& nodes, SpillStore& spills, Bucketing b,
                  ExtractResult* result)
      : octants_(octants), nodes_(nodes), spills_(spills), b_(b), result_(result) {}

  // Extracts the nodes of bucket `bucket`, whose leaves are `leaves` (key order).
  Status run(uint64_t bucket, const std::vector<uint64_t>& leaf_keys) {
    bucket_ = bucket;
    leaf_keys_ = &leaf_keys;
    hash_.reset(leaf_keys.size() + 64);
    for (uint64_t key : leaf_keys) WEAVER_RETURN_IF_ERROR(add_corners(octant_from_key(key)));
    WEAVER_RETURN_IF_ERROR(spills_.take(bucket, &incoming_));
    for (const SpillRecord& r : incoming_) hash_.add(r.key, r.mask);
    order_.resize(hash_.size());
    for (size_t i = 0; i < hash_.size(); ++i) order_[i] = {hash_.key_at(i), hash_.mask_at(i)};
    std::sort(order_.begin(), order_.end(),
              [](const SpillRecord& a, const SpillRecord& b) { return a.key < b.key; });
    for (const auto& [key, mask] : order_) {
      NodeKind kind = NodeKind::kAnchored;
      WEAVER_RETURN_IF_ERROR(classify(key, mask, &kind));
      const std::byte payload{static_cast<uint8_t>(kind)};
      WEAVER_RETURN_IF_ERROR(nodes_.append(key, &payload));
      count(kind);
    }
    return Status::Ok();
  }

 private:
  Status add_corners(const Octant& e) {
    for (int c = 0; c < 8; ++c) {
      const uint64_t key = node_key(octant_corner(e, c));
      const uint8_t bit = static_cast<uint8_t>(1u << (~c & 7));  // e lies on the far side of c
      const uint64_t owner = b_.of_key(key);
      if (owner == bucket_) {
        hash_.add(key, bit);
      } else {
        WEAVER_RETURN_IF_ERROR(spills_.add(owner, {key, bit}));
      }
    }
    return Status::Ok();
  }

  // The leaf holding pixel p, if any: the active bucket's leaves first, then
  // the octant table (pixels in earlier buckets, and leaves larger than a bucket).
  Status leaf_at(Coord p, Octant* leaf, bool* found) {
    const uint64_t pk = pixel_key(p);
    *found = false;
    if (b_.of_key(node_key(p)) == bucket_) {
      auto it = std::upper_bound(leaf_keys_->begin(), leaf_keys_->end(), pk);
      if (it != leaf_keys_->begin() && octant_contains_point(octant_from_key(*(it - 1)), p)) {
        *leaf = octant_from_key(*(it - 1));
        *found = true;
        return Status::Ok();
      }
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

  Status classify(uint64_t key, uint8_t mask, NodeKind* kind) {
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
  Status kind_on(Coord n, const Octant& leaf, uint8_t mask, NodeKind* kind) {
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
                                describe(leaf) + ": overlapping octants?");
    }
    *kind = inside == 1 ? NodeKind::kEdge : NodeKind::kFace;
    return Status::Ok();
  }

  // Names the coarse leaf and a finer element that has n as a corner.
  Status unbalanced(Coord n, const Octant& coarse, uint8_t mask) {
    std::string fine = "?";
    for (int d = 0; d < 8; ++d) {
      Coord p;
      Octant leaf;
      bool found = false;
      if (!((mask >> d) & 1) || !direction_pixel(n, d, &p)) continue;
      WEAVER_RETURN_IF_ERROR(leaf_at(p, &leaf, &found));
      if (found) {
        fine = describe(leaf);
        break;
      }
    }
    return Status::InvalidArgument("the octree is not 2:1 balanced: octant " + describe(coarse) +
                                   " and octant " + fine +
                                   " are face or edge neighbours more than one level apart");
  }

  void count(NodeKind k) {
    ++result_->nodes;
    if (k == NodeKind::kAnchored) ++result_->anchored;
    if (k == NodeKind::kEdge) ++result_->edge;
    if (k == NodeKind::kFace) ++result_->face;
  }

  BTree& octants_;
  BTree& nodes_;
  SpillStore& spills_;
  Bucketing b_;
  ExtractResult* result_;
  uint64_t bucket_ = 0;
  const std::vector<uint64_t>* leaf_keys_ = nullptr;
  NodeHash hash_;
  std::vector<SpillRecord> incoming_;
  std::vector<SpillRecord> order_;  // (key, mask) of the bucket's nodes
};

// One pass over the octant table: the finest level, and no two octants overlap.
Status scan_octants(BTree& octants, int* max_level) {
  *max_level = 0;
  BTreeCursor c;
  WEAVER_RETURN_IF_ERROR(octants.seek_cursor(0, &c));
  bool first = true;
  Octant prev{};
  while (c.valid()) {
    if (!octant_key_is_valid(c.key())) {
      return Status::Corruption(octants.file_name() + ": invalid octant key " +
                                std::to_string(c.key()));
    }
    const Octant o = octant_from_key(c.key());
    if (!first && octant_is_ancestor(prev, o)) {
      return Status::InvalidArgument("octants " + describe(prev) + " and " + describe(o) +
                                     " overlap");
    }
    *max_level = std::max<int>(*max_level, o.level);
    prev = o;
    first = false;
    WEAVER_RETURN_IF_ERROR(c.next());
  }
  return Status::Ok();
}

// The coarsest bucket level whose bucket, filled with finest leaves, fits in
// half the budget (S2 of the paper).
int bucket_level_for(uint64_t budget, int max_level) {
  int level = max_level;
  while (level > 0 && max_level - level < kMaxBucketDepth &&
         (kBytesPerLeaf << (3 * (max_level - level + 1))) <= budget / 2) {
    --level;
  }
  return level;
}

Status run_buckets(BTree& octants, BTree& nodes, const ExtractOptions& options,
                   const std::string& scratch, ExtractResult* result) {
  Bucketing b{result->bucket_level, 3 * (kMaxLevel - result->bucket_level)};
  SpillStore spills(scratch, std::max<uint64_t>(options.memory_bytes / 8, 1 << 12));
  BucketExtractor extractor(octants, nodes, spills, b, result);
  BTreeCursor c;
  WEAVER_RETURN_IF_ERROR(octants.seek_cursor(0, &c));
  std::vector<uint64_t> leaf_keys;
  while (c.valid() || !spills.empty()) {
    const uint64_t leaf_bucket = c.valid() ? b.of_key(octant_morton(octant_from_key(c.key())))
                                           : UINT64_MAX;
    const uint64_t bucket = spills.empty() ? leaf_bucket
                                           : std::min(leaf_bucket, spills.first_bucket());
    leaf_keys.clear();
    while (c.valid() && b.of_key(octant_morton(octant_from_key(c.key()))) == bucket) {
      leaf_keys.push_back(c.key());
      WEAVER_RETURN_IF_ERROR(c.next());
    }
    result->elements += leaf_keys.size();
    WEAVER_RETURN_IF_ERROR(extractor.run(bucket, leaf_keys));
    ++result->buckets;
    if (options.progress && result->buckets % 64 == 0) options.progress("nodes", result->nodes);
  }
  result->spilled = spills.records_added();
  result->spilled_to_disk = spills.records_written();
  return Status::Ok();
}

}  // namespace

Status extract_mesh(const std::string& db_dir, const ExtractOptions& options,
                    ExtractResult* result) {
  *result = ExtractResult{};
  std::unique_ptr<Database> db;
  WEAVER_RETURN_IF_ERROR(Database::open(db_dir, Database::Mode::kWrite, false, &db));
  std::unique_ptr<BTree> octants;
  // The octant table is read in order (cursor) plus aggregate hits near the
  // cursor: a modest pool keeps those pages cached.
  const uint64_t pool = std::min<uint64_t>(options.memory_bytes / 8, 32ull << 20);
  WEAVER_RETURN_IF_ERROR(db->open_table(kOctantTable, pool, &octants));
  int max_level = 0;
  WEAVER_RETURN_IF_ERROR(scan_octants(*octants, &max_level));
  result->bucket_level = options.bucket_level >= 0
                             ? std::min(options.bucket_level, kMaxLevel)
                             : bucket_level_for(options.memory_bytes, max_level);
  TableOptions topt;
  topt.key_kind = KeyKind::kNode;
  std::string error;
  topt.schema = *RecordSchema::parse(kNodeSchema, &error);
  topt.metadata = octants->options().metadata;
  std::unique_ptr<BTree> nodes;
  std::string file;
  WEAVER_RETURN_IF_ERROR(db->create_table(kNodeTable, topt, std::min<uint64_t>(pool, 8ull << 20),
                                          &nodes, &file));
  const std::string scratch = db_dir + "/tmp-extract-" + std::to_string(::getpid());
  Status st = run_buckets(*octants, *nodes, options, scratch, result);
  if (st.ok()) st = nodes->commit();
  if (st.ok()) st = db->commit({{kNodeTable, file}});
  if (!st.ok()) {
    nodes.reset();
    db->abandon(file);
    return st;
  }
  result->node_table_bytes = nodes->file_bytes();
  return Status::Ok();
}

}  // namespace weaver
