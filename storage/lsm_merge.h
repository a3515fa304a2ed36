// The LSM's merging iterator: reads the memtable and a suffix of the runs
// (newest first) as one sequence in key order.  For each key the newest
// entry wins and the older ones are skipped; tombstones are yielded (for
// merges that must keep them) or skipped (for readers).
#pragma once

#include <cstdint>
#include <vector>

#include "storage/btree_cursor.h"
#include "storage/lsm.h"

namespace weaver {

class LsmMergeIterator {
 public:
  // Sources: runs [first_run, end) and, with_memtable, the memtable (sorted
  // first by the caller); positioned at the first key >= from.
  Status init(LsmTree& tree, size_t first_run, bool with_memtable, uint64_t from,
              bool keep_tombstones);

  bool valid() const { return winner_ >= 0; }
  uint64_t key() const { return key_; }
  bool tombstone() const;
  const std::byte* payload() const;  // without the tombstone byte
  Status next();

 private:
  struct Source {
    bool mem = false;
    bool flags = false;
    bool valid = false;
    size_t pos = 0;  // memtable position
    BTreeCursor cursor;
  };
  uint64_t source_key(const Source& s) const;
  Status advance(Source& s);
  // Picks the least key; skips the older entries for it, and tombstones
  // unless they are kept.
  Status settle();
  Status report_shadow(size_t older_source);

  const Memtable* mem_ = nullptr;
  const LsmShadowHook* on_shadow_ = nullptr;
  std::vector<Source> sources_;  // newest first
  bool keep_tombstones_ = false;
  int winner_ = -1;
  uint64_t key_ = 0;
};

// A Cursor over the live records of an LsmTree.
class LsmCursor final : public Cursor {
 public:
  explicit LsmCursor(std::unique_ptr<LsmMergeIterator> it) : it_(std::move(it)) {}
  bool valid() const override { return it_->valid(); }
  uint64_t key() const override { return it_->key(); }
  const std::byte* payload() const override { return it_->payload(); }
  Status next() override { return it_->next(); }

 private:
  std::unique_ptr<LsmMergeIterator> it_;
};

}  // namespace weaver
