// The entry of both extraction algorithms (extract.h), where the budget goes,
// and the bucketing policy of the sort: the bucket level a budget affords.
#include "extract/extract.h"

#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cstdio>

#include "db/database.h"
#include "db/leaf_reader.h"
#include "db/node_table.h"
#include "db/octant_table.h"
#include "extract/bucket_worker.h"
#include "extract/extract_search.h"
#include "extract/extract_sort.h"
#include "extract/ghost_layer.h"
#include "extract/node_classifier.h"
#include "schema/node.h"
#include "schema/octant.h"
#include "util/octant_key_stream.h"

namespace weaver {
namespace {

// Bytes of memory per finest-level leaf in the active bucket: its key, room
// for 1.5 nodes in a half-full hash table (1.5 x 9 bytes / 0.5 for
// NodeHash's key and mask; NodeWords' word is 8) and the sort vector.
constexpr uint64_t kBytesPerLeaf = 8 + 27 + 16;

// No bucket holds more than 8^kMaxBucketDepth finest leaves (kLevel) or
// most_bucket_leaves() leaves (kLeaves) whatever the budget: its hash table
// then stays in the core's own cache.  Larger buckets save spills and the
// reader's work on them, but where most corners are hashed (random octrees)
// they cost cache misses on every corner once the table leaves the L2.
//   - With a 1 MiB L2 (the AMD EPYC machine of stops 70-76): 8192 leaves
//     against 32768 took 0.81x the time of a 1M-leaf random octree's
//     extract, 0.73x a 1M sphere's, 0.97x 10M random, 0.96x the 2 Hz
//     basin's.  With a word a slot (node_words.h) and blocks of up to 4096
//     leaves unhashed, 16384 took the 2 Hz and 1 Hz basins' extract to
//     0.955x of 8192 (farm-bench) but random 1M's to about 1.1x
//     (p4est_bench, lnodes over weaver 8.5x and 10.1x against 10.7x and
//     10.2x).
//   - With a 2 MiB L2 (the Intel machine of stop 77): 16384 took the 2 Hz
//     extract to 0.90x of 8192 (farm-bench, 3 pairs) and random 1M's
//     lnodes over weaver to 10.07x against 9.73x and 9.89x.
// So 8192 leaves a MiB of L2, 8192 to 16384 (8192 where the system does
// not say).
constexpr int kMaxBucketDepth = 6;
constexpr uint64_t kLeavesPerL2MiB = uint64_t{1} << 13;
constexpr uint64_t kMostBucketLeaves = uint64_t{1} << 14;

uint64_t most_bucket_leaves() {
  static const uint64_t most = [] {
    const long l2 = ::sysconf(_SC_LEVEL2_CACHE_SIZE);
    const uint64_t mib = l2 > 0 ? static_cast<uint64_t>(l2) >> 20 : 1;
    return std::clamp<uint64_t>(mib * kLeavesPerL2MiB, kLeavesPerL2MiB, kMostBucketLeaves);
  }();
  return most;
}

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
  // Each classifier's cache of leaves: a worker's each, or the one of the
  // search or of one thread.
  const bool search = o.algorithm == ExtractOptions::Algorithm::kSearch;
  const uint64_t classifiers = search || o.threads <= 1 ? 1 : static_cast<uint64_t>(o.threads);
  // (4 slots for each leaf of the largest bucket: with 2 for buckets of
  // 16384, random 1M's extract took 1.05x the time on stop 76's AMD
  // machine, p4est_bench.)
  const uint64_t cache_bytes =
      NodeClassifier::kSlotsPerLeaf * sizeof(uint64_t) * std::bit_ceil(most_bucket_leaves());
  classifier_cache = plan.take("classifier caches", 1, 64, classifiers * cache_bytes) / classifiers;
  if (search) {
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

namespace {

// The buckets (into result) and the node table's options, from the leaves.
Status plan_extract(BTree& octants, const ExtractOptions& options, const ExtractMemory& memory,
                    ExtractResult* result, TableOptions* topt) {
  if (options.buckets == ExtractOptions::Buckets::kLevel) {
    int max_level = 0;
    WEAVER_RETURN_IF_ERROR(finest_level_of(octants, &max_level));
    result->bucket_level = options.bucket_level >= 0 ? std::min(options.bucket_level, kMaxLevel)
                                                     : bucket_level_for(memory.bucket, max_level);
  } else {
    result->bucket_leaves =
        options.bucket_leaves > 0
            ? options.bucket_leaves
            : std::clamp<uint64_t>(memory.bucket / kBytesPerLeaf, 1, most_bucket_leaves());
  }
  topt->key_kind = KeyKind::kNode;
  std::string error;
  topt->schema = *RecordSchema::parse(kNodeSchema, &error);
  topt->metadata = octants.options().metadata;
  topt->packed = options.packed;
  return Status::Ok();
}

// The sort's nodes appended to a table.
NodeBatchSink appender(BTree& nodes) {
  return [&nodes](const uint64_t* keys, const std::byte* kinds, size_t n) {
    return nodes.append_batch(keys, kinds, n);
  };
}

}  // namespace

Status derive_nodes(const Database& db, const ExtractOptions& options,
                    const std::string& scratch_dir, const NodeBatchSink& out,
                    ExtractResult* result) {
  *result = ExtractResult{};
  const ExtractMemory memory(options);
  std::unique_ptr<BTree> octants;
  WEAVER_RETURN_IF_ERROR(db.open_table(kOctantTable, memory.octant_pool, &octants));
  TableOptions unused;
  WEAVER_RETURN_IF_ERROR(plan_extract(*octants, options, memory, result, &unused));
  return extract_by_sort(db, *octants, out, scratch_dir, memory, options, result);
}

Status extract_mesh(const std::string& db_dir, const ExtractOptions& options,
                    ExtractResult* result) {
  *result = ExtractResult{};
  const ExtractMemory memory(options);
  std::unique_ptr<Database> own;
  Database* db = options.writer;
  if (db == nullptr) {
    WEAVER_RETURN_IF_ERROR(Database::open(db_dir, Database::Mode::kWrite, false, &own));
    db = own.get();
  }
  std::unique_ptr<BTree> octants;
  WEAVER_RETURN_IF_ERROR(db->open_table(kOctantTable, memory.octant_pool, &octants));
  TableOptions topt;
  WEAVER_RETURN_IF_ERROR(plan_extract(*octants, options, memory, result, &topt));
  std::unique_ptr<BTree> nodes;
  std::string file;
  WEAVER_RETURN_IF_ERROR(db->create_table(kNodeTable, topt, memory.node_pool, &nodes, &file));
  const std::string scratch = db_dir + "/tmp-extract-" + std::to_string(::getpid());
  Status st;
  if (options.algorithm == ExtractOptions::Algorithm::kSearch) {
    result->bucket_level = -1;
    result->bucket_leaves = 0;
    st = extract_by_search(*octants, *nodes, scratch, memory.search_store,
                           NodeClassifier::cache_bits_for(memory.classifier_cache),
                           options.store == ExtractOptions::Store::kLsm, result);
  } else {
    st = extract_by_sort(*db, *octants, appender(*nodes), scratch, memory, options, result);
  }
  WEAVER_RETURN_IF_ERROR(options.stage && options.writer != nullptr
                             ? db->stage(kNodeTable, file, nodes, st)
                             : db->publish(kNodeTable, file, nodes, st));
  result->node_table_bytes = nodes->file_bytes();
  return Status::Ok();
}

namespace {

// Sends this rank's ghosts to the ranks that need them and takes its own
// (after an error, sends nothing but still takes part).
Status exchange_ghosts(BTree* octants, const ExtractPart& part, const std::vector<uint64_t>& start,
                       int rank, const RankExchange& exchange, Status st,
                       std::vector<uint64_t>* ghosts, ShardExchangeCounts* counts) {
  std::vector<std::vector<uint64_t>> outgoing(start.size() - 1);
  if (st.ok() && part.start < part.stop)
    st = ghost_leaves(*octants, part.first_leaf, part.stop, start, rank, &outgoing);
  std::vector<std::string> blobs(outgoing.size()), received;
  for (size_t s = 0; st.ok() && s < outgoing.size(); ++s) {
    blobs[s] = encode_octant_keys(outgoing[s]);
    counts->ghosts_sent += outgoing[s].size();
    counts->bytes_sent += blobs[s].size();
  }
  if (!st.ok()) blobs.assign(outgoing.size(), std::string());
  const Status exchanged = exchange(blobs, &received);
  WEAVER_RETURN_IF_ERROR(st);
  WEAVER_RETURN_IF_ERROR(exchanged);
  for (const std::string& b : received) {  // earlier ranks first: sorted
    counts->bytes_received += b.size();
    if (!decode_octant_keys(b, ghosts)) return Status::Corruption("a ghost layer cut short");
  }
  counts->ghosts_received = ghosts->size();
  return Status::Ok();
}

}  // namespace

Status extract_shard(const std::string& db_dir, const ExtractOptions& options, int rank, int ranks,
                     const std::string& file, const RankExchange& exchange, ExtractResult* result,
                     ShardEntry* entry, ShardExchangeCounts* counts) {
  *result = ExtractResult{};
  *entry = ShardEntry{file};
  *counts = ShardExchangeCounts{};
  const ExtractMemory memory(options);
  std::unique_ptr<Database> db;
  std::unique_ptr<BTree> octants;
  std::vector<uint64_t> first_leaf, start(ranks + 1, UINT64_MAX);
  ExtractPart part;
  // Up to the exchange, an error still takes part in it (sending nothing).
  Status st = Database::open(db_dir, Database::Mode::kRead, false, &db);
  if (st.ok() && !options.staged_octants.empty()) {
    st = db->stage_shards(kOctantTable, options.staged_octants);
  }
  if (st.ok()) st = db->open_table(kOctantTable, memory.octant_pool, &octants);
  if (st.ok()) st = cut_equal_runs(*octants, ranks, &first_leaf, &start);
  if (st.ok()) {
    part.start = start[rank];
    part.stop = start[rank + 1];
    part.first_leaf = first_leaf[rank];
  }
  WEAVER_RETURN_IF_ERROR(
      exchange_ghosts(octants.get(), part, start, rank, exchange, st, &part.ghosts, counts));
  if (part.start >= part.stop) return Status::Ok();  // owns no node
  TableOptions topt;
  WEAVER_RETURN_IF_ERROR(plan_extract(*octants, options, memory, result, &topt));
  std::unique_ptr<BTree> nodes;
  WEAVER_RETURN_IF_ERROR(create_shard_table(db_dir, file, topt, memory.node_pool, &nodes));
  const std::string scratch_dir =
      db_dir + "/tmp-extract-" + std::to_string(::getpid()) + "-" + std::to_string(rank);
  st =
      extract_by_sort(*db, *octants, appender(*nodes), scratch_dir, memory, options, result, &part);
  return finish_shard(db_dir, nodes, st, shard_place_among(start, rank), entry,
                      &result->node_table_bytes);
}

}  // namespace weaver
