// The entry of both extraction algorithms (extract.h), where the budget goes,
// and the bucketing policy of the sort: the bucket level a budget affords.
#include "extract/extract.h"

#include <unistd.h>

#include <algorithm>

#include "db/database.h"
#include "db/leaf_reader.h"
#include "db/node_table.h"
#include "db/octant_table.h"
#include "extract/extract_search.h"
#include "extract/extract_sort.h"
#include "extract/node_classifier.h"
#include "schema/node.h"
#include "schema/octant.h"

namespace weaver {
namespace {

// Bytes of memory per finest-level leaf in the active bucket: its key, room
// for 1.5 nodes in a half-full hash table (1.5 x 9 bytes / 0.5), the sort
// vector, and the classifier's index of the bucket's leaves.
constexpr uint64_t kBytesPerLeaf = 8 + 27 + 16 + NodeClassifier::kIndexBytesPerLeaf;
// No bucket holds more than 8^kMaxBucketDepth finest leaves (kLevel) or
// kMaxBucketLeaves leaves (kLeaves) whatever the budget: its hash table then
// stays in the CPU caches.  Larger buckets only save spills, which cost far
// less than cache misses on every corner.
constexpr int kMaxBucketDepth = 6;
constexpr uint64_t kMaxBucketLeaves = uint64_t{1} << 15;

// The finest level: from the counts the table's writer kept, else one pass.
Status finest_level_of(BTree& octants, int* max_level) {
  LevelCounts levels{};
  if (levels_from_metadata(octants.options().metadata, &levels)) {
    *max_level = finest_level(levels);
    return Status::Ok();
  }
  *max_level = 0;
  LeafReader r;
  WEAVER_RETURN_IF_ERROR(r.open(octants));
  while (r.valid()) {
    *max_level = std::max<int>(*max_level, octant_from_key(r.key()).level);
    WEAVER_RETURN_IF_ERROR(r.next());
  }
  return Status::Ok();
}

// The coarsest bucket level whose bucket, filled with finest leaves, fits in
// a worker's bucket share (S2 of the paper).
int bucket_level_for(uint64_t bucket_bytes, int max_level) {
  int level = max_level;
  while (level > 0 && max_level - level < kMaxBucketDepth &&
         (kBytesPerLeaf << (3 * (max_level - level + 1))) <= bucket_bytes) {
    --level;
  }
  return level;
}

}  // namespace

ExtractMemory::ExtractMemory(const ExtractOptions& o) : plan(o.memory) {
  // The octant table is read in order (cursor) plus aggregate hits near the
  // cursor: a modest pool keeps those pages cached.
  octant_pool = plan.take("octant table pool", 1, 8, 32ull << 20);
  // A sorted append touches only the right spine of the node table.
  node_pool = plan.take("node table pool", 1, 32, 8ull << 20);
  if (o.algorithm == ExtractOptions::Algorithm::kSearch) {
    // Every vertex searches the store: the larger its cache, the fewer
    // searches go to disk.
    search_store = plan.take("search node store", 1, 2);
    return;
  }
  // Pixels spilled to later buckets wait here; past it they go to a file.
  spill = plan.take("spill cap", 1, 8);
  if (o.threads <= 1) {
    // The one active bucket: the larger, the fewer spills (S2).
    bucket = plan.take("bucket", 1, 2);
    return;
  }
  const uint64_t n = static_cast<uint64_t>(o.threads);
  // Each worker holds one bucket (at the default budget and 2 threads, as
  // large as kMaxBucketDepth allows); the aggregate hits of each go through
  // its own pool (a pool serves one thread).
  bucket = plan.take("buckets (all workers)", 1, 8) / n;
  worker_pool = plan.take("worker pools (all workers)", 1, 16) / n;
  // Buckets read ahead so that workers never wait for the reader: 8 a
  // thread measured 1.63x on 2 cores, 2 only 1.41x (extract_parallel.cc).
  in_flight = plan.take("buckets in flight", 1, 2);
}

Status extract_mesh(const std::string& db_dir, const ExtractOptions& options,
                    ExtractResult* result) {
  *result = ExtractResult{};
  const ExtractMemory memory(options);
  std::unique_ptr<Database> db;
  WEAVER_RETURN_IF_ERROR(Database::open(db_dir, Database::Mode::kWrite, false, &db));
  std::unique_ptr<BTree> octants;
  WEAVER_RETURN_IF_ERROR(db->open_table(kOctantTable, memory.octant_pool, &octants));
  if (options.buckets == ExtractOptions::Buckets::kLevel) {
    int max_level = 0;
    WEAVER_RETURN_IF_ERROR(finest_level_of(*octants, &max_level));
    result->bucket_level = options.bucket_level >= 0 ? std::min(options.bucket_level, kMaxLevel)
                                                     : bucket_level_for(memory.bucket, max_level);
  } else {
    result->bucket_leaves =
        options.bucket_leaves > 0
            ? options.bucket_leaves
            : std::clamp<uint64_t>(memory.bucket / kBytesPerLeaf, 1, kMaxBucketLeaves);
  }
  TableOptions topt;
  topt.key_kind = KeyKind::kNode;
  std::string error;
  topt.schema = *RecordSchema::parse(kNodeSchema, &error);
  topt.metadata = octants->options().metadata;
  topt.packed = options.packed;
  std::unique_ptr<BTree> nodes;
  std::string file;
  WEAVER_RETURN_IF_ERROR(db->create_table(kNodeTable, topt, memory.node_pool, &nodes, &file));
  const std::string scratch = db_dir + "/tmp-extract-" + std::to_string(::getpid());
  Status st;
  if (options.algorithm == ExtractOptions::Algorithm::kSearch) {
    result->bucket_level = -1;
    result->bucket_leaves = 0;
    st = extract_by_search(*octants, *nodes, scratch, memory.search_store,
                           options.store == ExtractOptions::Store::kLsm, result);
  } else {
    st = extract_by_sort(*db, *octants, *nodes, scratch, memory, options, result);
  }
  WEAVER_RETURN_IF_ERROR(db->publish(kNodeTable, file, nodes, st));
  result->node_table_bytes = nodes->file_bytes();
  return Status::Ok();
}

}  // namespace weaver
