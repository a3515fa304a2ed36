#include "extract/extract_parallel.h"

#include <algorithm>
#include <atomic>
#include <memory>

#include "db/octant_table.h"
#include "util/ordered_run.h"

namespace weaver {

Status write_bucket(const BucketTask& t, const NodeBatchSink& nodes, uint64_t elements,
                    const ExtractOptions& options, ExtractResult* result) {
  WEAVER_RETURN_IF_ERROR(nodes(t.node_keys.data(), t.node_kinds.data(), t.node_keys.size()));
  result->elements += t.counts.elements;
  result->nodes += t.counts.nodes;
  result->anchored += t.counts.anchored;
  result->edge += t.counts.edge;
  result->face += t.counts.face;
  ++result->buckets;
  if (options.progress) {
    options.progress(result->elements, double(result->elements) / std::max<uint64_t>(1, elements));
  }
  return Status::Ok();
}

namespace {

constexpr int kTasksPerThread = 8;

// Memory a task holds while in flight: its leaves, its incoming pixels and
// (once done) its nodes, about 1.2 per leaf.  Estimated from the inputs so
// that it is the same when the task is added and when it is removed.
uint64_t task_bytes(const BucketTask& t) {
  return t.leaf_keys.size() * (8 + 20) + t.incoming.size() * 2 * sizeof(SpillRecord);
}

// The memory a task's buffers hold, in use or not.
uint64_t held_bytes(const BucketTask& t) {
  return t.leaf_keys.capacity() * 8 + t.incoming.capacity() * sizeof(SpillRecord) +
         t.node_keys.capacity() * 8 + t.node_kinds.capacity();
}

}  // namespace

Status run_parallel(const Database& db, BTree& octants, const NodeBatchSink& nodes,
                    const BucketPolicy& policy, SpillStore& spills, const ExtractMemory& memory,
                    const ExtractOptions& options, ExtractResult* result) {
  const int n = options.threads;
  // Each worker reads the octant table through its own handle: a buffer pool
  // serves one thread.
  std::vector<std::unique_ptr<BTree>> handles(n);
  std::vector<std::unique_ptr<BucketWorker>> workers;
  for (auto& h : handles) {
    WEAVER_RETURN_IF_ERROR(db.open_table(kOctantTable, memory.worker_pool, &h));
    workers.push_back(std::make_unique<BucketWorker>(*h, policy));
  }
  LeafReader c;
  Status read_st = c.open(octants, policy.first_leaf);
  if (!read_st.ok()) return read_st;
  BucketReader reader(c, policy, spills);
  // Buckets are read, and their nodes written, by whichever worker is free
  // (util/ordered_run.h): there is no reader or writer thread beside the
  // workers.  A read (the leaves, the reader's spills) and a write (the
  // nodes) share nothing, so one thread reads while another writes; each
  // has its own status.  Read ahead far enough that workers never wait for
  // the oldest (8 tasks a thread measured 1.63x on 2 cores, 2 tasks only
  // 1.41x), but within the in-flight share of the budget.
  std::atomic<uint64_t> in_flight_bytes{0};
  const uint64_t elements = octants.size();  // for the writer's progress
  Status write_st;
  const size_t slots = static_cast<size_t>(kTasksPerThread * n);
  const uint64_t keep_bytes = memory.in_flight / slots;
  auto make = [&](BucketTask* t) {
    bool more = false;
    if (read_st.ok()) read_st = reader.next(t, &more);
    if (!read_st.ok() || !more) return false;
    t->status = Status::Ok();
    in_flight_bytes += task_bytes(*t);
    return true;
  };
  auto work = [&](int i, BucketTask* t) { t->status = workers[i]->run(*t); };
  auto write = [&](BucketTask* t) {
    if (write_st.ok()) write_st = t->status;
    if (write_st.ok()) write_st = write_bucket(*t, nodes, elements, options, result);
    in_flight_bytes -= task_bytes(*t);
    // Its buffers stay for the next task made in this object (freed and
    // faulted in again for every bucket, they cost the second thread a
    // tenth more CPU), unless they hold more than the object's share of
    // the in-flight budget: the objects are more than the budget's room
    // for tasks may allow.  (The nodes' vectors keep their size: the next
    // run resizes them, and zeroes only what grows.)
    if (held_bytes(*t) > keep_bytes) {
      *t = BucketTask{};
    } else {
      t->leaf_keys.clear();
      t->incoming.clear();
    }
    return write_st.ok();
  };
  OrderedRun<BucketTask> run(slots, make, work, write,
                             [&] { return in_flight_bytes < memory.in_flight; });
  run.make_beside_write();
  run.go(n);
  // A failed read ends the making: the buckets before it are written, and
  // the read's error is the run's unless a write failed first.
  return write_st.ok() ? read_st : write_st;
}

}  // namespace weaver
