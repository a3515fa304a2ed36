// The LSM store: writes go to a memtable (storage/lsm_memtable.h); a full
// memtable becomes an immutable sorted run, and each run is a B+tree file
// bulk-built by sorted append, the same kind of file a table is.  Reads merge
// the memtable and the runs, newest first: a newer entry hides older ones for
// the same key, and a tombstone hides the key.  compact() merges everything
// into one run with no tombstones, which is byte for byte the B+tree a
// sorted append of the live records would build.
//
// Run format: a run whose records may include tombstones carries one more
// leading payload byte, "lsm_tombstone" (1 = deleted); a run with no
// tombstones (every run written by a merge that reaches the oldest data, and
// every flush while no run exists) is a plain table.
//
// Compaction policy, size-tiered with fan-in 4: a flush adds a run of tier 0;
// whenever the newest four runs share a tier (their sizes within a factor of
// 4 of memtable size x 4^tier) they merge into one of the next tier.  Each
// record is rewritten about log4(n / memtable) times, the least write work
// for a bounded number of runs (at most 3 per tier), which suits weaver's
// workloads: out-of-order builds (import, search extraction) that write
// everything, then read it in key order after compact().  A leveled policy
// would keep point reads cheaper during the build at several times the
// writes.
//
// A compacted store (one plain run, empty memtable) answers every read from
// that run's B+tree directly.  Ids: rank() and select() are O(log n) then,
// and a merging scan otherwise.  size() is exact while every write
// is known to be new or known to replace (appends, puts and erases on a
// compacted or empty store, puts that ask for *replaced); after a blind put
// it is an upper bound until count() or compact().
//
// Files live in one directory: run-<n>.bt and LSM (the run list, rewritten
// atomically on commit(); open() reads it and removes runs it does not name).
// Not thread-safe.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "storage/btree.h"
#include "storage/lsm_memtable.h"
#include "storage/store.h"

namespace weaver {

// Called when an entry hides an older entry of the same key (newer and older
// payloads; null for a tombstone or a put of a null payload), wherever that
// is found: a put over a memtable entry, a merge, a read.  An error it
// returns fails that operation.  The default (none) lets the newer entry win silently; a
// caller for whom a repeated key is bad input reports it here.
using LsmShadowHook =
    std::function<Status(uint64_t key, const std::byte* newer, const std::byte* older)>;

struct LsmOptions {
  TableOptions table;  // key kind, payload schema, page size, metadata
  LsmShadowHook on_shadow;
  uint64_t memtable_bytes = 64ull << 20;  // flush when the memtable holds this much
  uint64_t run_pool_bytes = 1ull << 20;   // buffer pool of each run
};

class LsmMergeIterator;

class LsmTree final : public Store {
 public:
  // Creates an empty store in dir (made if missing; it must hold no LSM).
  static Status create(const std::string& dir, const LsmOptions& options,
                       std::unique_ptr<LsmTree>* out);
  // Opens the committed state of the store in dir; the table options come
  // from its runs (options.table is ignored).
  static Status open(const std::string& dir, const LsmOptions& options,
                     std::unique_ptr<LsmTree>* out);
  ~LsmTree() override;

  Status append(uint64_t key, const std::byte* payload) override;
  Status put(uint64_t key, const std::byte* payload, bool* replaced) override;
  Status erase(uint64_t key) override;
  Status get(uint64_t key, std::byte* payload_out, bool* found) override;
  Status floor(uint64_t key, uint64_t* key_out, std::byte* payload_out, bool* found) override;
  Status seek(uint64_t key, std::unique_ptr<Cursor>* out) override;
  Status rank(uint64_t key, uint64_t* out) override;
  Status select(uint64_t index, uint64_t* key_out, std::byte* payload_out) override;
  uint64_t size() const override { return size_; }
  uint32_t payload_size() const override { return payload_; }
  // Flushes the memtable to a run, syncs, and rewrites the run list.
  Status commit() override;

  // The exact record count, by a merging scan unless size() is exact.
  Status count(uint64_t* out);
  bool size_exact() const { return size_exact_; }
  // Merges the memtable and every run into one run, dropping tombstones.
  Status compact();
  // Writes the live records, in key order, into `out` (an empty tree) by
  // sorted append; the store is unchanged.  How a build ends in a table
  // file that lives elsewhere (a database's).
  Status compact_into(BTree& out);

  size_t run_count() const { return runs_.size(); }
  uint64_t file_bytes() const;                                   // of the runs
  uint64_t runs_written() const { return runs_written_; }        // flushes and merges
  uint64_t records_written() const { return records_written_; }  // into runs, in all
  const TableOptions& options() const { return o_.table; }
  // The single run of a compacted store, else null.
  BTree* compacted_run();

 private:
  struct Run {
    std::unique_ptr<BTree> tree;
    std::string file;    // name within dir_
    bool flags = false;  // has the tombstone byte
    int tier = 0;
  };
  friend class LsmMergeIterator;

  LsmTree(std::string dir, const LsmOptions& o);
  Status new_run_file(bool flags, std::unique_ptr<BTree>* tree, std::string* file);
  Status flush();
  // Merges the runs [first, runs_.size()) and, with_memtable, the memtable
  // (newer than every run) into one run that replaces them.
  Status merge_tail(size_t first, bool with_memtable);
  Status maybe_merge();
  Status write_merged(LsmMergeIterator& it, BTree& out, bool flags, uint64_t* written);
  Status write_run_list();
  void retire(const std::string& file);
  Status live_floor(uint64_t key, uint64_t* key_out, bool* found, size_t* skip);
  Status make_iterator(uint64_t from, bool keep_tombstones, std::unique_ptr<LsmMergeIterator>* it);

  std::string dir_;
  LsmOptions o_;
  uint32_t payload_ = 0;
  Memtable mem_;
  std::vector<Run> runs_;               // oldest first
  std::vector<std::string> committed_;  // the run files the committed list names
  std::vector<std::string> obsolete_;   // merged away, named by that list
  uint64_t next_file_ = 1;
  uint64_t size_ = 0;
  bool size_exact_ = true;
  bool has_max_ = false;
  uint64_t max_key_ = 0;  // the largest key ever written (for append)
  uint64_t runs_written_ = 0, records_written_ = 0;
  std::vector<std::byte> scratch_;          // a run record: flag byte + payload
  std::vector<std::byte> floor_candidate_;  // live_floor's other record buffer
};

}  // namespace weaver
