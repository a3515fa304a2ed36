// The leaf directory's life in a B+tree: built after enough lookups of an
// unchanged tree, dropped on any change, read by point lookups.
#include <algorithm>

#include "storage/btree.h"

namespace weaver {

using page::PageType;

uint32_t BTree::leaf_prefetch_bytes(bool whole) const {
  // A plain leaf's search reads the header and the key column: those lines
  // only are prefetched (the whole page was 7% slower at 10M random gets in
  // the pool and 20% at 100K: a core has about a dozen line-fill buffers,
  // and prefetches beyond them stall it).
  if (!options_.packed) return page::kPageHeaderBytes + 8 * leaf_cap_;
  if (whole) return options_.page_size;
  // A point lookup in a packed leaf reads its index (block bases and table),
  // then one block: the index's lines, as many as a leaf of the tree's mean
  // entry count has, and one more, are prefetched (10M random gets in the
  // pool: 2.8-3.2M/s, against 2.5-2.65M/s prefetching the whole page).
  const uint64_t mean = record_count_ / std::max<uint64_t>(page_count_, 1);
  return static_cast<uint32_t>(
      std::min<uint64_t>(options_.page_size, shape_.index_bytes(mean) + 64));
}

uint64_t BTree::directory_threshold() const {
  // page_count_ bounds the leaf count.  Building costs a few nanoseconds a
  // leaf (its internal pages are in the pool), a lookup a few hundred: after
  // a page count's eighth of lookups, a tree that changes now and then
  // spends at most about a fifth more on rebuilding than on looking up.
  if (LeafDirectory::bytes_for(page_count_) > dir_budget_) return 0;
  return page_count_ / 8 + 64;
}

Status BTree::locate(uint64_t key, bool whole_leaf, PageRef* leaf, uint32_t* dir_leaf,
                     uint64_t* first_rank) {
  if (!has_directory() && ++reads_since_change_ == directory_threshold()) {
    WEAVER_RETURN_IF_ERROR(build_directory());
  }
  if (!has_directory()) {
    *dir_leaf = kNoDirLeaf;
    if (first_rank != nullptr) *first_rank = 0;
    Path path;
    return descend(key, &path, leaf, first_rank, whole_leaf);
  }
  const LeafDirectory& dir = *dir_;
  const uint32_t j = dir.find(key);
  *dir_leaf = j;
  if (first_rank != nullptr) *first_rank = dir.first_rank(j);
  return fetch_typed(dir.page(j), leaf_type(), leaf, leaf_prefetch_bytes(whole_leaf));
}

const std::byte* BTree::peek_plain_leaf(uint64_t key, uint32_t* dir_leaf) {
  if (options_.packed || !has_directory()) return nullptr;
  const LeafDirectory& dir = *dir_;
  const uint32_t j = dir.find(key);
  const uint32_t page_no = dir.page(j);
  if (page_no == 0 || page_no > page_count_) return nullptr;  // the general path reports it
  const std::byte* d = pool_->peek(page_no, leaf_prefetch_bytes(false));
  if (d == nullptr) return nullptr;
  // The payload's line, guessed from where key falls between the leaf's
  // fence and the next, is asked for with the key column: where keys are
  // spread evenly (a region of one level) it arrives with them instead of
  // after the search.  A wrong guess costs one line of bandwidth.
  const uint64_t n = j + 1 < dir.size() ? dir.first_rank(j + 1) - dir.first_rank(j) : 0;
  if (payload_ > 0 && n > 0) {
    const uint64_t lo = dir.fence(j), span = dir.fence(j + 1) - lo;
    const auto guess = static_cast<uint64_t>(double(key - lo) / double(span) * double(n));
    __builtin_prefetch(d + page::kPageHeaderBytes + 8 * size_t{leaf_cap_} +
                       size_t{payload_} * std::min(guess, n - 1));
  }
  if (page::type(d) != PageType::kLeaf) return nullptr;
  *dir_leaf = j;
  return d;
}

Status BTree::prepare_lookups() {
  if (shards_ != nullptr || has_directory() || directory_threshold() == 0) return Status::Ok();
  seal_tail();
  return build_directory();
}

Status BTree::build_directory() {
  dir_.reset();
  auto dir = std::make_shared<LeafDirectory>();
  dir->reserve(page_count_);  // bounds the leaves, and fits the budget (directory_threshold)
  if (height_ == 1) dir->add(0, root_, 0);
  uint64_t rank = 0;
  if (height_ > 1) WEAVER_RETURN_IF_ERROR(add_leaves_below(*dir, root_, 0, 0, &rank));
  if (height_ >= 1) dir_ = std::move(dir);
  return Status::Ok();
}

// Adds the leaves under the internal page `page_no` at `level`, whose
// subtree the tree routes keys >= fence to.  A child's fence is its key in
// the page, except the first child's: it inherits the page's (its own key
// may be stale, and routes nothing).
Status BTree::add_leaves_below(LeafDirectory& dir, uint32_t page_no, uint32_t level, uint64_t fence,
                               uint64_t* rank) {
  PageRef r;
  WEAVER_RETURN_IF_ERROR(fetch_typed(page_no, PageType::kInternal, &r));
  const uint32_t n = page::count(r.data());
  if (n == 0) return Status::Corruption(where(page_no) + ": empty internal page");
  const page::InternalView v = internal(r);
  for (uint32_t i = 0; i < n; ++i) {
    const uint64_t f = i == 0 ? fence : v.key(i);
    if (!dir.empty() && f < dir.last_fence()) {
      return Status::Corruption(where(page_no) + ": separator keys out of order");
    }
    if (level + 2 == height_) {
      dir.add(f, v.child(i), *rank);
      *rank += v.subtree_count(i);
    } else {
      WEAVER_RETURN_IF_ERROR(add_leaves_below(dir, v.child(i), level + 1, f, rank));
    }
  }
  return Status::Ok();
}

}  // namespace weaver
