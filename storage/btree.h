// A paged B+tree of fixed-size records (page format: storage/page_format.h).
//
// Sorted append fills leaves full from left to right and grows the index on
// the right spine: no splits, about 1% index overhead.  Random inserts split
// in place; a split at the right end of the tree keeps the left page full.
// Deletes free pages that become empty (no merging of half-empty pages).
// Internal entries carry subtree record counts, so rank and select are
// O(log n): ids in weaver are ranks.  Point lookups in a tree that has
// stopped changing go through an in-memory directory of its leaves
// (storage/leaf_directory.h), paid for from the pool's budget.
//
// Not thread-safe.  Changes reach the file on commit() (or when the buffer
// pool evicts); commit() writes the header last and syncs.
#pragma once

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "storage/btree_cursor.h"
#include "storage/buffer_pool.h"
#include "storage/file.h"
#include "storage/leaf_directory.h"
#include "storage/packed_leaf.h"
#include "storage/page_format.h"
#include "storage/store.h"

namespace weaver {

class ShardSet;

class BTree final : public Store {
 public:
  // pool_bytes bounds the tree's memory: its buffer pool, and a 32nd of it
  // for the leaf directory.
  static constexpr uint64_t kDirectoryShare = 32;
  // Makes an empty tree in `file` (which should be empty).
  static Status create(std::unique_ptr<File> file, const TableOptions& options, uint64_t pool_bytes,
                       std::unique_ptr<BTree>* out);
  // Opens an existing tree, verifying the header.
  static Status open(std::unique_ptr<File> file, uint64_t pool_bytes, std::unique_ptr<BTree>* out);
  // A read-only tree over shards: B+tree files holding disjoint, increasing
  // key ranges (storage/shard_set.h), answering every read below as one tree
  // of all their records would (ranks are global; cursors go on from shard
  // to shard).  Its options are the first shard's.  Writes are refused.
  static Status open_sharded(std::vector<std::unique_ptr<BTree>> shards,
                             std::unique_ptr<BTree>* out);
  ~BTree() override;
  // The number of shards of a sharded tree; 0 for a tree of one file.
  size_t shard_count() const;

  Status append(uint64_t key, const std::byte* payload) override;
  // Sorted append of n records at once (keys strictly increasing, all greater
  // than the tree's last key; payloads packed, n x payload_size bytes).
  // Copies whole runs into the rightmost leaf.  On an out-of-order key,
  // nothing is appended.
  Status append_batch(const uint64_t* keys, const std::byte* payloads, size_t n);
  Status put(uint64_t key, const std::byte* payload, bool* replaced) override;
  Status erase(uint64_t key) override;
  Status get(uint64_t key, std::byte* payload_out, bool* found) override;
  Status floor(uint64_t key, uint64_t* key_out, std::byte* payload_out, bool* found) override;
  Status seek(uint64_t key, std::unique_ptr<Cursor>* out) override;
  Status rank(uint64_t key, uint64_t* out) override;
  Status select(uint64_t index, uint64_t* key_out, std::byte* payload_out) override;
  uint64_t size() const override { return record_count_; }
  uint32_t payload_size() const override { return payload_; }
  Status commit() override;

  // rank() and get() in one descent: the key's position, and whether it is there.
  Status rank_exact(uint64_t key, uint64_t* rank, bool* present);
  // floor() and the rank of the key it finds in one descent (a point query
  // that wants the element's id and material: half the descents of the two).
  // rank may be null: then nothing is counted, and this is floor().
  // recycle_leaf: the leaf read is offered to the pool as its next victim
  // (a sparse walk over a large table, that would otherwise fill every frame
  // with pages it will not ask again, each frame fresh memory to fault in).
  // The keys around key's floor, for a caller that asks for many floors
  // near one another: the packed block (up to page::kPackedBlock keys, into
  // keys[0, *count)) whose keys are the floors of every k in [keys[0],
  // *limit).  *count is 0 when the floor is not in key's leaf, or the
  // table is sharded or plain, or key is UINT64_MAX: floor() answers those.
  Status floor_block(uint64_t key, uint64_t* keys, uint32_t* count, uint64_t* limit);
  // The last key <= key, its payload and its rank.  walk: one of a walk of
  // keys in ascending order that reads each leaf about once (a batch of
  // sparse points): the leaf is kept for the floors after it, which mostly
  // land in it, and offered to the pool as its next victim once the walk
  // leaves it.
  Status floor_rank(uint64_t key, uint64_t* key_out, std::byte* payload_out, uint64_t* rank,
                    bool* found, bool walk = false);

  // The leaf where key is or would be: all its keys, decoded, and the rank of
  // its first record.  For callers that rank many nearby keys at once
  // (src/mesh/corner_batch.h): one descent and decode for a leaf's worth.
  // With payloads, also their payloads, packed row-wise.
  Status leaf_keys(uint64_t key, std::vector<uint64_t>* keys, uint64_t* first_rank,
                   std::vector<std::byte>* payloads = nullptr);

  // A concrete cursor (no virtual calls on the scan path).
  Status seek_cursor(uint64_t key, BTreeCursor* cursor);
  // The same for a reader of keys alone: packed leaves are decoded without
  // their payload columns.  The cursor's payload() must not be called.
  Status seek_keys(uint64_t key, BTreeCursor* cursor);

  // Walks the whole tree and checks every invariant of page_format.h.
  Status check_invariants();

  const TableOptions& options() const { return options_; }
  void set_metadata(std::string metadata) { options_.metadata = std::move(metadata); }
  uint32_t height() const { return height_; }
  uint32_t page_count() const { return page_count_; }
  // Leaves in the lookup directory: 0 until it is built, and after a change.
  uint32_t directory_leaves() const { return dir_ ? dir_->size() : 0; }
  // Builds the lookup directory now, where the budget allows it, rather than
  // after the first page count's eighth of lookups: a server about to answer
  // lookups pays for it before its first request, not during it.
  Status prepare_lookups();
  // What the lookup directory may take (by default a 32nd of the pool's
  // bytes).  A tree asked mostly point lookups at random (an Explorer's)
  // gains more from its directory than from as many bytes of cached pages.
  void set_directory_budget(uint64_t bytes) { dir_budget_ = bytes; }
  // The lookup directory, once built (null before), to share with other
  // trees open on the same file in the same state: it is never changed,
  // only dropped (on any change) or replaced.
  std::shared_ptr<const LeafDirectory> directory() const { return dir_; }
  // Takes another tree's directory.  REQUIRES: that tree is open on this
  // file, in the state this one reads (a server's threads, one snapshot).
  void share_directory(std::shared_ptr<const LeafDirectory> dir) { dir_ = std::move(dir); }
  uint64_t file_bytes() const {
    return uint64_t{shard_headers_ == 0 ? 1 : shard_headers_} * page::kFileHeaderBytes +
           uint64_t{page_count_} * options_.page_size;
  }
  const std::string& file_name() const { return file_->name(); }
  BufferPool& pool() { return *pool_; }

 private:
  friend class BTreeCursor;
  friend class ShardSet;
  using Path = TreePath;
  static constexpr int kMaxHeight = TreePath::kMaxDepth;
  struct Split {  // a new right sibling to hook into the parent
    uint64_t key;
    uint64_t count;
    uint32_t page_no;
    uint64_t left_count;
  };

  BTree(std::unique_ptr<File> file, const TableOptions& options, uint64_t pool_bytes);
  Status write_header();
  // The error of every write to a sharded tree.
  Status sharded_write() const;
  std::string where(uint32_t page_no) const;

  // prefetch_bytes: how much of the page to prefetch on a pool hit.
  Status fetch(uint32_t page_no, PageRef* ref,
               uint32_t prefetch_bytes = BufferPool::kPrefetchBytes);
  Status fetch_typed(uint32_t page_no, page::PageType type, PageRef* ref,
                     uint32_t prefetch_bytes = BufferPool::kPrefetchBytes);
  Status new_page(page::PageType type, bool at_end, PageRef* ref);
  Status free_page(uint32_t page_no);
  page::LeafView leaf(const PageRef& r) const { return {r.data(), leaf_cap_, payload_}; }
  page::LeafView leaf(const std::byte* pg) const {
    return {const_cast<std::byte*>(pg), leaf_cap_, payload_};
  }
  page::PageType leaf_type() const {
    return options_.packed ? page::PageType::kPackedLeaf : page::PageType::kLeaf;
  }

  // Leaf access for both formats (packed leaves are decoded on the fly).
  Status open_packed(const PageRef& lf, page::PackedLeaf* reader);
  // The first slot with a key >= key (> key when upper), and the keys either
  // side of it (as PackedLeaf::bound), from one search.
  // payload_next: the caller reads the payload at the answer next.
  Status leaf_bound(const PageRef& lf, uint64_t key, bool upper, uint32_t* pos,
                    uint64_t* below = nullptr, uint64_t* at = nullptr, bool payload_next = false);
  Status leaf_key(const PageRef& lf, uint32_t i, uint64_t* key);
  Status leaf_payload(const PageRef& lf, uint32_t i, std::byte* out);
  // All entries of a leaf: keys, and payloads packed row-wise unless vals is null.
  Status leaf_entries(const PageRef& lf, std::vector<uint64_t>* keys, std::vector<std::byte>* vals);
  page::InternalView internal(const PageRef& r) const { return {r.data(), internal_cap_}; }

  // Where a key is, or would be inserted: the pinned leaf, the path to it,
  // the leaf's entry count and the slot (lower bound) of the key.
  struct LeafSlot {
    Path path;
    PageRef leaf;
    uint32_t n = 0;
    uint32_t pos = 0;
    bool exact = false;  // the key is present at pos
  };
  // The leaf a lookup reads: through the leaf directory when there is one,
  // else by descent.  whole_leaf: the caller reads all of it (else one entry).
  // *dir_leaf is the leaf's place in the directory, or kNoDirLeaf.  With
  // first_rank, also the rank of the leaf's first record.
  // REQUIRES: height_ > 0.
  static constexpr uint32_t kNoDirLeaf = UINT32_MAX;
  Status locate(uint64_t key, bool whole_leaf, PageRef* leaf, uint32_t* dir_leaf,
                uint64_t* first_rank = nullptr);
  // How many lookups pass unchanged before the directory is built (enough
  // that building costs a fraction of what they cost), or 0: never, it would
  // not fit in its share of the memory budget.
  uint64_t directory_threshold() const;
  Status build_directory();
  Status add_leaves_below(LeafDirectory& dir, uint32_t page_no, uint32_t level, uint64_t fence,
                          uint64_t* rank);
  // Every change calls this: the directory no longer matches the tree.
  void changed() {
    dir_.reset();
    held_ = HeldLeaf{};
    reads_since_change_ = 0;
  }
  bool has_directory() const { return dir_ && !dir_->empty(); }
  // How much of a leaf to prefetch on a pool hit, for a reader of all of it
  // (whole) or of one entry.
  uint32_t leaf_prefetch_bytes(bool whole) const;
  // The fast path of get, floor and rank_exact on plain leaves: the leaf the
  // directory routes key to, when there is a directory and the pool holds
  // the leaf, read without a pin (nothing else uses the pool until the
  // lookup is done), and its place in the directory; else null, and the
  // lookup takes the general path.
  const std::byte* peek_plain_leaf(uint64_t key, uint32_t* dir_leaf);
  // For floor, when every key of the leaf `key` is routed to is > key (a
  // separator went stale when its key was erased): the leaf before it, or
  // *first_leaf.  dir_leaf as locate gave it.
  // *routed: the directory's index of lf when the floor is in the leaf the
  // directory routes key to, else kNoDirLeaf.
  Status floor_rank_at(uint64_t key, uint64_t* key_out, std::byte* payload_out, uint64_t* rank,
                       bool* found, PageRef* lf, uint32_t* routed);
  Status preceding_leaf(uint64_t key, uint32_t dir_leaf, PageRef* leaf, bool* first_leaf);
  // REQUIRES: height_ > 0.  With rank_before, also counts the records in the
  // subtrees left of the path.
  Status descend(uint64_t key, Path* path, PageRef* leaf, uint64_t* rank_before = nullptr,
                 bool whole_leaf = true);
  // seek_cursor and seek_keys: the cursor at the first key >= key.
  Status position(uint64_t key, bool keys_only, BTreeCursor* cursor);
  // For a change at key (put, erase): its leaf slot, by descent (the path
  // is needed to split or free pages).
  Status find(uint64_t key, LeafSlot* slot);
  Status descend_edge(uint32_t page_no, int level, bool rightmost, Path* path, PageRef* leaf);
  Status add_to_path_counts(const Path& path, int upto, int64_t delta);
  bool path_is_rightmost(const Path& path);
  void bump_spine_counts(int levels, uint64_t delta = 1);

  // insert
  Status insert_new_root_leaf(uint64_t key, const std::byte* payload);
  Status split_leaf(PageRef& leaf, uint32_t pos, uint64_t key, const std::byte* payload,
                    bool rightmost, Split* split);
  // `above` is added to the counts of the path's entries above the split level.
  Status insert_into_parents(Path& path, Split split, bool rightmost, int64_t above = 1);
  Status split_internal(PageRef& node, uint32_t pos, const Split& entry, bool rightmost,
                        Split* split);
  Status grow_root(const Split& split, bool at_end, PageRef* root);

  // append fast path: the right spine, pinned while appends run
  Status load_spine();
  void drop_spine();
  Status append_new_leaf(uint64_t key, const std::byte* payload);

  // packed leaves: the spine's leaf is kept decoded in tail_ while appends
  // run, and packed into its page before anything reads or writes it back.
  void seal_tail();
  Status load_tail();
  Status init_leaf(PageRef& lf, uint64_t key, const std::byte* payload);
  Status packed_rewrite(LeafSlot& s, std::vector<uint64_t>& keys, std::vector<std::byte>& vals,
                        int64_t delta);
  std::vector<std::pair<uint32_t, uint32_t>> pack_pieces(const std::vector<uint64_t>& keys,
                                                         const std::vector<std::byte>& vals,
                                                         bool halve);
  Status packed_write(std::byte* pg, const std::vector<uint64_t>& keys,
                      const std::vector<std::byte>& vals, uint32_t from, uint32_t to);
  Status packed_edit(uint64_t key, const std::byte* payload, bool erase, bool* replaced);

  // erase
  Status remove_empty_child(Path& path, int level);
  Status collapse_root();

  Status check_subtree(uint32_t page_no, int level, uint64_t lo, uint64_t hi, uint64_t* count,
                       uint64_t* first_key, uint64_t* last_key);

  std::unique_ptr<File> file_;
  TableOptions options_;
  uint32_t payload_ = 0;
  uint32_t leaf_cap_ = 0;
  uint32_t internal_cap_ = 0;
  std::unique_ptr<BufferPool> pool_;

  uint32_t height_ = 0;
  uint32_t root_ = 0;
  uint32_t page_count_ = 0;
  uint32_t free_head_ = 0;
  uint64_t record_count_ = 0;

  bool spine_valid_ = false;
  PageRef spine_[kMaxHeight];  // spine_[0] root ... spine_[height_-1] rightmost leaf
  bool max_known_ = false;
  uint64_t max_key_ = 0;

  page::PackedShape shape_;
  std::unique_ptr<page::PackedLeafBuilder> tail_;  // packed only
  std::unique_ptr<page::PackedLeafBuilder> edit_;  // packed only: re-packs edited leaves
  bool tail_dirty_ = false;                        // tail_ holds entries its page does not
  page::PackedLeaf reader_;                        // for point lookups

  // A sharded tree (open_sharded) hands every read to its shards; each shard
  // knows the one after it, where its cursors go on.
  std::unique_ptr<ShardSet> shards_;
  BTree* next_shard_ = nullptr;
  uint32_t shard_headers_ = 0;  // file headers in a sharded tree's files (one a shard)

  std::shared_ptr<const LeafDirectory> dir_;  // null until built, and after any change
  // A walk's leaf (floor_rank): a packed leaf of the directory, pinned and
  // opened, and the keys the directory routes to it, [lo, hi).
  struct HeldLeaf {
    PageRef ref;
    page::PackedLeaf reader;
    uint32_t dir_leaf = 0;
    uint64_t lo = 1, hi = 0;  // none
  };
  HeldLeaf held_;
  // The walk's floor from the held leaf; false (nothing set) when key is
  // not routed to it or lies before its first key.
  bool held_floor(uint64_t key, uint64_t* key_out, std::byte* payload_out, uint64_t* rank);
  // Holds lf, the leaf floor_rank_at read, if the directory routed its key
  // to it (routed, its index); else recycles it.  REQUIRES: none held.
  Status hold_leaf(uint32_t routed, PageRef lf);
  void release_held();  // recycled: the walk has left it
  uint64_t reads_since_change_ = 0;
  uint64_t dir_budget_ = 0;  // the directory's share of the memory budget
};

}  // namespace weaver
