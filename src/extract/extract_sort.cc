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
#include "extract/bucket_worker.h"
#include "extract/extract_parallel.h"
#include "extract/extract_search.h"
#include "extract/node_classifier.h"
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
// half the budget (S2 of the paper).
int bucket_level_for(uint64_t budget, int max_level) {
  int level = max_level;
  while (level > 0 && max_level - level < kMaxBucketDepth &&
         (kBytesPerLeaf << (3 * (max_level - level + 1))) <= budget / 2) {
    --level;
  }
  return level;
}

// One thread: read, extract and write each bucket in turn.
Status run_serial(BTree& octants, BTree& nodes, const Bucketing& b, SpillStore& spills,
                  const ExtractOptions& options, ExtractResult* result) {
  BucketWorker worker(octants, b);
  LeafReader c;
  WEAVER_RETURN_IF_ERROR(c.open(octants));
  BucketTask task;
  bool more = true;
  while (true) {
    WEAVER_RETURN_IF_ERROR(read_bucket(c, b, spills, &task, &more));
    if (!more) return Status::Ok();
    WEAVER_RETURN_IF_ERROR(worker.run(task));
    WEAVER_RETURN_IF_ERROR(write_bucket(task, nodes, result));
    if (options.progress && result->buckets % 64 == 0) options.progress("nodes", result->nodes);
  }
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
  WEAVER_RETURN_IF_ERROR(finest_level_of(*octants, &max_level));
  result->bucket_level = options.bucket_level >= 0
                             ? std::min(options.bucket_level, kMaxLevel)
                             : bucket_level_for(options.memory_bytes, max_level);
  TableOptions topt;
  topt.key_kind = KeyKind::kNode;
  std::string error;
  topt.schema = *RecordSchema::parse(kNodeSchema, &error);
  topt.metadata = octants->options().metadata;
  topt.packed = options.packed;
  std::unique_ptr<BTree> nodes;
  std::string file;
  WEAVER_RETURN_IF_ERROR(db->create_table(kNodeTable, topt, std::min<uint64_t>(pool, 8ull << 20),
                                          &nodes, &file));
  const std::string scratch = db_dir + "/tmp-extract-" + std::to_string(::getpid());
  Status st;
  if (options.algorithm == ExtractOptions::Algorithm::kSearch) {
    result->bucket_level = 0;
    st = extract_by_search(*octants, *nodes, scratch,
                           std::max<uint64_t>(options.memory_bytes / 2, 1 << 20),
                           options.store == ExtractOptions::Store::kLsm, result);
  } else {
    const Bucketing b{result->bucket_level, 3 * (kMaxLevel - result->bucket_level)};
    SpillStore spills(scratch, std::max<uint64_t>(options.memory_bytes / 8, 1 << 12));
    if (options.threads > 1) {
      st = run_parallel(*db, *octants, *nodes, b, spills, options, result);
    } else {
      st = run_serial(*octants, *nodes, b, spills, options, result);
    }
    result->spilled = spills.records_added();
    result->spilled_to_disk = spills.records_written();
  }
  WEAVER_RETURN_IF_ERROR(db->publish(kNodeTable, file, nodes, st));
  result->node_table_bytes = nodes->file_bytes();
  return Status::Ok();
}

}  // namespace weaver
