// Two-level bucket sort (paper, section 4), generalised to 3D, to non-cube
// domains and to any bucket size.
//
// High-level buckets are runs of leaves in Z-order (bucket_worker.h): the
// paper's aligned octants of one level, or about K leaves each.  The leaves
// of the active bucket are its low-level buckets.  Each leaf
// contributes its 8 corners as nodal pixels, tagged with the direction (one
// of the 8 cells around the node) in which the leaf lies; a pixel that falls
// into a later bucket (the active bucket's far faces) is spilled and picked
// up when that bucket becomes active.  Duplicates merge in a hash table by
// ORing direction bits.
//
// Dangling or anchored is decided by NodeClassifier (node_classifier.h)
// from the direction bits merged here, with aggregate hits on the active
// bucket's leaves.
#include "extract/extract_sort.h"

#include "db/leaf_reader.h"
#include "extract/bucket_worker.h"
#include "extract/extract_parallel.h"
#include "extract/ghost_layer.h"

namespace weaver {
namespace {

// One thread: read, extract and write each bucket in turn.
Status run_serial(BTree& octants, const NodeBatchSink& nodes, const BucketPolicy& policy,
                  SpillStore& spills, const ExtractOptions& options, ExtractResult* result) {
  BucketWorker worker(octants, policy);
  LeafReader c;
  WEAVER_RETURN_IF_ERROR(c.open(octants, policy.first_leaf));
  BucketReader reader(c, policy, spills);
  BucketTask task;
  while (true) {
    bool more = true;
    WEAVER_RETURN_IF_ERROR(reader.next(&task, &more));
    if (!more) return Status::Ok();
    WEAVER_RETURN_IF_ERROR(worker.run(task));
    WEAVER_RETURN_IF_ERROR(write_bucket(task, nodes, octants.size(), options, result));
  }
}

}  // namespace

Status extract_by_sort(const Database& db, BTree& octants, const NodeBatchSink& nodes,
                       const std::string& scratch_path, const ExtractMemory& memory,
                       const ExtractOptions& options, ExtractResult* result, ExtractPart* part) {
  BucketPolicy policy{result->bucket_level, result->bucket_leaves};
  policy.cache_bits = NodeClassifier::cache_bits_for(memory.classifier_cache);
  SpillStore spills(scratch_path, memory.spill);
  if (part != nullptr) {
    policy.start = part->start;
    policy.stop = part->stop;
    policy.first_leaf = part->first_leaf;
    policy.ghosts = &part->ghosts;
    WEAVER_RETURN_IF_ERROR(spill_ghost_corners(part->ghosts, part->start, part->stop, spills));
  }
  const Status st = options.threads > 1
                        ? run_parallel(db, octants, nodes, policy, spills, memory, options, result)
                        : run_serial(octants, nodes, policy, spills, options, result);
  result->spilled = spills.records_added();
  result->spilled_to_disk = spills.records_written();
  return st;
}

}  // namespace weaver
