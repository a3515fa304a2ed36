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
// Dangling or anchored is decided by NodeClassifier (node_classifier.h)
// from the direction bits merged here, with aggregate hits on the active
// bucket's leaves.
#include <algorithm>
#include <unistd.h>

#include "db/database.h"
#include "db/node_table.h"
#include "db/octant_table.h"
#include "extract/extract.h"
#include "extract/extract_search.h"
#include "extract/node_classifier.h"
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

struct Bucketing {
  int level;  // bucket level: edge 2^(20-level)
  int shift;  // bits of a node key below the bucket id
  uint64_t of_key(uint64_t node_key) const { return node_key >> shift; }
};

class BucketExtractor {
 public:
  BucketExtractor(BTree& octants, BTree& nodes, SpillStore& spills, Bucketing b,
                  ExtractResult* result)
      : classifier_(octants), nodes_(nodes), spills_(spills), b_(b), result_(result) {}

  // Extracts the nodes of bucket `bucket`, whose leaves are `leaves` (key order).
  Status run(uint64_t bucket, const std::vector<uint64_t>& leaf_keys) {
    bucket_ = bucket;
    classifier_.set_local(&leaf_keys, bucket, b_.shift);
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
      WEAVER_RETURN_IF_ERROR(classifier_.classify(key, mask, &kind));
      const std::byte payload{static_cast<uint8_t>(kind)};
      WEAVER_RETURN_IF_ERROR(nodes_.append(key, &payload));
      count_kind(kind, result_);
    }
    return Status::Ok();
  }

 private:
  Status add_corners(const Octant& e) {
    for (int c = 0; c < 8; ++c) {
      const uint64_t key = node_key(octant_corner(e, c));
      const uint8_t bit = corner_direction_bit(c);
      const uint64_t owner = b_.of_key(key);
      if (owner == bucket_) {
        hash_.add(key, bit);
      } else {
        WEAVER_RETURN_IF_ERROR(spills_.add(owner, {key, bit}));
      }
    }
    return Status::Ok();
  }

  NodeClassifier classifier_;
  BTree& nodes_;
  SpillStore& spills_;
  Bucketing b_;
  ExtractResult* result_;
  uint64_t bucket_ = 0;
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
      return Status::InvalidArgument("octants " + describe_octant(prev) + " and " + describe_octant(o) +
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
  Status st;
  if (options.algorithm == ExtractOptions::Algorithm::kSearch) {
    result->bucket_level = 0;
    st = extract_by_search(*octants, *nodes, scratch + ".bt",
                           std::max<uint64_t>(options.memory_bytes / 2, 1 << 20), result);
  } else {
    st = run_buckets(*octants, *nodes, options, scratch, result);
  }
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
