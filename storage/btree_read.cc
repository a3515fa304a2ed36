// B+tree lookups: descent, get, floor, rank, select, cursors.
#include <algorithm>
#include <cstring>
#include <vector>

#include "storage/btree.h"
#include "storage/page_search.h"
#include "storage/shard_set.h"

namespace weaver {

using page::PageType;

Status BTree::descend(uint64_t key, Path* path, PageRef* leaf_ref, uint64_t* rank_before,
                      bool whole_leaf) {
  path->depth = 0;
  uint32_t pg = root_;
  for (uint32_t level = 0; level + 1 < height_; ++level) {
    PageRef r;
    WEAVER_RETURN_IF_ERROR(fetch_typed(pg, PageType::kInternal, &r));
    const uint32_t n = page::count(r.data());
    if (n == 0) return Status::Corruption(where(pg) + ": empty internal page");
    const page::InternalView v = internal(r);
    page::prefetch_keys(v.key_at(0), n);
    const uint32_t idx = page::child_index(v.key_at(0), n, key);
    if (rank_before != nullptr) {
      for (uint32_t i = 0; i < idx; ++i) *rank_before += v.subtree_count(i);
    }
    path->e[path->depth++] = {pg, idx};
    pg = v.child(idx);
  }
  return fetch_typed(pg, leaf_type(), leaf_ref, leaf_prefetch_bytes(whole_leaf));
}

Status BTree::find(uint64_t key, LeafSlot* s) {
  WEAVER_RETURN_IF_ERROR(descend(key, &s->path, &s->leaf));
  s->n = page::count(s->leaf.data());
  uint64_t at = 0;
  WEAVER_RETURN_IF_ERROR(leaf_bound(s->leaf, key, false, &s->pos, nullptr, &at));
  s->exact = s->pos < s->n && at == key;
  return Status::Ok();
}

// ---------------------------------------------------------------------------
// Leaf access for both formats.
// ---------------------------------------------------------------------------

Status BTree::open_packed(const PageRef& lf, page::PackedLeaf* reader) {
  if (!reader->open(lf.data(), shape_)) {
    return Status::Corruption(where(lf.page_no()) + ": packed leaf layout does not fit the page");
  }
  return Status::Ok();
}

Status BTree::leaf_bound(const PageRef& lf, uint64_t key, bool upper, uint32_t* pos,
                         uint64_t* below, uint64_t* at, bool payload_next) {
  if (!options_.packed) {
    const page::LeafView v = leaf(lf);
    const uint32_t n = page::count(lf.data());
    *pos = upper ? page::upper_bound(v.key_at(0), n, key) : page::lower_bound(v.key_at(0), n, key);
    if (below != nullptr && *pos > 0) *below = v.key(*pos - 1);
    if (at != nullptr && *pos < n) *at = v.key(*pos);
    return Status::Ok();
  }
  WEAVER_RETURN_IF_ERROR(open_packed(lf, &reader_));
  if (!reader_.bound(key, upper, pos, below, at, payload_next && payload_ > 0)) {
    return Status::Corruption(where(lf.page_no()) + ": packed key block out of bounds");
  }
  return Status::Ok();
}

Status BTree::leaf_key(const PageRef& lf, uint32_t i, uint64_t* key) {
  if (!options_.packed) {
    *key = leaf(lf).key(i);
    return Status::Ok();
  }
  WEAVER_RETURN_IF_ERROR(open_packed(lf, &reader_));
  if (!reader_.key(i, key)) {
    return Status::Corruption(where(lf.page_no()) + ": packed key block out of bounds");
  }
  return Status::Ok();
}

Status BTree::leaf_payload(const PageRef& lf, uint32_t i, std::byte* out) {
  if (payload_ == 0) return Status::Ok();
  if (!options_.packed) {
    std::memcpy(out, leaf(lf).value(i), payload_);
    return Status::Ok();
  }
  WEAVER_RETURN_IF_ERROR(open_packed(lf, &reader_));
  reader_.payload(i, out);
  return Status::Ok();
}

Status BTree::leaf_entries(const PageRef& lf, std::vector<uint64_t>* keys,
                           std::vector<std::byte>* vals) {
  const uint32_t n = page::count(lf.data());
  keys->resize(n);
  if (vals != nullptr) vals->resize(size_t{n} * payload_);
  if (!options_.packed) {
    const page::LeafView v = leaf(lf);
    if (n > 0) std::memcpy(keys->data(), v.key_at(0), 8 * size_t{n});
    if (vals != nullptr && n > 0 && payload_ > 0)
      std::memcpy(vals->data(), v.value(0), vals->size());
    return Status::Ok();
  }
  WEAVER_RETURN_IF_ERROR(open_packed(lf, &reader_));
  if (!reader_.decode(keys->data(), vals != nullptr ? vals->data() : nullptr)) {
    return Status::Corruption(where(lf.page_no()) + ": packed key block out of bounds");
  }
  return Status::Ok();
}

// Descends from page_no (at `level`) to a leaf along the leftmost or the
// rightmost children, recording the path from `level` on.
Status BTree::descend_edge(uint32_t page_no, int level, bool rightmost, Path* path,
                           PageRef* leaf_ref) {
  path->depth = level;
  uint32_t pg = page_no;
  for (uint32_t l = level; l + 1 < height_; ++l) {
    PageRef r;
    WEAVER_RETURN_IF_ERROR(fetch_typed(pg, PageType::kInternal, &r));
    const uint32_t n = page::count(r.data());
    if (n == 0) return Status::Corruption(where(pg) + ": empty internal page");
    const uint32_t idx = rightmost ? n - 1 : 0;
    path->e[path->depth++] = {pg, idx};
    pg = internal(r).child(idx);
  }
  WEAVER_RETURN_IF_ERROR(fetch_typed(pg, leaf_type(), leaf_ref));
  if (page::count(leaf_ref->data()) == 0 && height_ > 1) {
    return Status::Corruption(where(pg) + ": empty leaf page");
  }
  return Status::Ok();
}

Status BTree::get(uint64_t key, std::byte* payload_out, bool* found) {
  if (shards_) return shards_->get(key, payload_out, found);
  *found = false;
  seal_tail();
  if (height_ == 0) return Status::Ok();
  uint32_t dir_leaf = 0, pos = 0;
  if (const std::byte* d = peek_plain_leaf(key, &dir_leaf)) {
    const page::LeafView v = leaf(d);
    const uint32_t n = page::count(d);
    pos = page::lower_bound(v.key_at(0), n, key);
    *found = pos < n && v.key(pos) == key;
    if (*found && payload_out != nullptr) std::memcpy(payload_out, v.value(pos), payload_);
    return Status::Ok();
  }
  PageRef lf;
  uint64_t at = 0;
  WEAVER_RETURN_IF_ERROR(locate(key, false, &lf, &dir_leaf));
  WEAVER_RETURN_IF_ERROR(leaf_bound(lf, key, false, &pos, nullptr, &at, payload_out != nullptr));
  *found = pos < page::count(lf.data()) && at == key;
  if (*found && payload_out != nullptr) return leaf_payload(lf, pos, payload_out);
  return Status::Ok();
}

Status BTree::floor(uint64_t key, uint64_t* key_out, std::byte* payload_out, bool* found) {
  if (shards_) return shards_->floor(key, key_out, payload_out, found);
  return floor_rank(key, key_out, payload_out, nullptr, found);
}

Status BTree::floor_block(uint64_t key, uint64_t* keys, uint32_t* count, uint64_t* limit) {
  *count = 0;
  // (No limit is past UINT64_MAX.)
  if (shards_ || !options_.packed || key == UINT64_MAX) return Status::Ok();
  seal_tail();
  if (height_ == 0) return Status::Ok();
  PageRef lf;
  uint32_t dir_leaf = 0;
  WEAVER_RETURN_IF_ERROR(locate(key, false, &lf, &dir_leaf));
  WEAVER_RETURN_IF_ERROR(open_packed(lf, &reader_));
  if (!reader_.floor_block(key, keys, count, limit)) {
    return Status::Corruption(where(lf.page_no()) + ": packed key block out of bounds");
  }
  // Past the leaf's last block the next key is in another leaf: the block
  // answers up to its own last key, or to key (whose floor that is).
  if (*count > 0 && *limit == 0) *limit = std::max(keys[*count - 1], key) + 1;
  return Status::Ok();
}

Status BTree::floor_rank(uint64_t key, uint64_t* key_out, std::byte* payload_out, uint64_t* rank,
                         bool* found, bool walk) {
  if (walk && held_floor(key, key_out, payload_out, rank)) {
    *found = true;
    return Status::Ok();
  }
  // Let go of the held leaf first: a walk pins no more pages than a lookup.
  if (walk) release_held();
  PageRef lf;
  uint32_t routed = kNoDirLeaf;
  WEAVER_RETURN_IF_ERROR(floor_rank_at(key, key_out, payload_out, rank, found, &lf, &routed));
  return walk ? hold_leaf(routed, std::move(lf)) : Status::Ok();
}

// A sorted walk of a million random points over the 2 Hz basin's 1.3B
// leaves lands about 8 points in each leaf it reads: the 7 after the first
// skip the directory's search, the pool's lookup and the opening of the
// packed page.
bool BTree::held_floor(uint64_t key, uint64_t* key_out, std::byte* payload_out, uint64_t* rank) {
  if (key < held_.lo || key >= held_.hi) return false;
  uint32_t ub = 0;
  uint64_t below = 0;
  if (!held_.reader.bound(key, true, &ub, &below, nullptr,
                          payload_out != nullptr && payload_ > 0) ||
      ub == 0) {
    return false;  // before the leaf's first key, or a damaged block: the general path's
  }
  *key_out = below;
  if (rank != nullptr) *rank = dir_->first_rank(held_.dir_leaf) + ub - 1;
  if (payload_out != nullptr && payload_ > 0) held_.reader.payload(ub - 1, payload_out);
  return true;
}

void BTree::release_held() {
  held_.ref.recycle();
  held_.lo = 1, held_.hi = 0;
}

Status BTree::hold_leaf(uint32_t routed, PageRef lf) {
  if (!lf || routed == kNoDirLeaf || !options_.packed || !has_directory()) {
    lf.recycle();
    return Status::Ok();
  }
  const uint32_t j = routed;
  WEAVER_RETURN_IF_ERROR(open_packed(lf, &held_.reader));
  held_.ref = std::move(lf);
  held_.dir_leaf = j;
  held_.lo = dir_->fence(j);
  held_.hi = j + 1 < dir_->size() ? dir_->fence(j + 1) : UINT64_MAX;
  return Status::Ok();
}

Status BTree::floor_rank_at(uint64_t key, uint64_t* key_out, std::byte* payload_out, uint64_t* rank,
                            bool* found, PageRef* leaf_ref, uint32_t* routed) {
  PageRef& lf = *leaf_ref;
  *routed = kNoDirLeaf;
  if (shards_) {  // each shard ranks its own keys: the set adds them up
    WEAVER_RETURN_IF_ERROR(shards_->floor(key, key_out, payload_out, found));
    return *found ? shards_->rank_exact(*key_out, rank, found) : Status::Ok();
  }
  *found = false;
  seal_tail();
  if (height_ == 0) return Status::Ok();
  uint32_t dir_leaf = 0, ub = 0;
  if (const std::byte* d = peek_plain_leaf(key, &dir_leaf)) {
    const page::LeafView v = leaf(d);
    ub = page::upper_bound(v.key_at(0), page::count(d), key);
    if (ub > 0) {
      *found = true;
      *key_out = v.key(ub - 1);
      if (rank != nullptr) *rank = dir_->first_rank(dir_leaf) + ub - 1;
      if (payload_out != nullptr) std::memcpy(payload_out, v.value(ub - 1), payload_);
      return Status::Ok();
    }
  }
  uint64_t below = 0, before = 0;  // the key at ub - 1; the records before the leaf
  // The records before the leaf are counted on the way down only when asked.
  WEAVER_RETURN_IF_ERROR(locate(key, false, &lf, &dir_leaf, rank != nullptr ? &before : nullptr));
  WEAVER_RETURN_IF_ERROR(leaf_bound(lf, key, true, &ub, &below, nullptr, payload_out != nullptr));
  if (ub == 0) {
    // The floor ends the preceding leaf (or there is none): its rank is the
    // one just before this leaf's first record.
    lf.reset();
    bool first_leaf = false;
    WEAVER_RETURN_IF_ERROR(preceding_leaf(key, dir_leaf, &lf, &first_leaf));
    if (first_leaf) return Status::Ok();
    ub = page::count(lf.data());
    WEAVER_RETURN_IF_ERROR(leaf_key(lf, ub - 1, &below));
    *found = true;
    *key_out = below;
    if (rank != nullptr) *rank = before - 1;
    if (payload_out != nullptr) return leaf_payload(lf, ub - 1, payload_out);
    return Status::Ok();
  }
  *found = true;
  *key_out = below;
  *routed = dir_leaf;  // (kNoDirLeaf without a directory)
  if (rank != nullptr) *rank = before + ub - 1;
  if (payload_out != nullptr) return leaf_payload(lf, ub - 1, payload_out);
  return Status::Ok();
}

Status BTree::preceding_leaf(uint64_t key, uint32_t dir_leaf, PageRef* lf, bool* first_leaf) {
  *first_leaf = false;
  if (dir_leaf != kNoDirLeaf) {
    *first_leaf = dir_leaf == 0;
    if (*first_leaf) return Status::Ok();
    WEAVER_RETURN_IF_ERROR(fetch_typed(dir_->page(dir_leaf - 1), leaf_type(), lf));
    if (page::count(lf->data()) > 0) return Status::Ok();
    return Status::Corruption(where(lf->page_no()) + ": empty leaf page");
  }
  Path path;
  WEAVER_RETURN_IF_ERROR(descend(key, &path, lf));
  lf->reset();
  int d = path.depth - 1;
  while (d >= 0 && path.e[d].index == 0) --d;
  *first_leaf = d < 0;
  if (*first_leaf) return Status::Ok();
  uint32_t left_child;
  {
    PageRef p;
    WEAVER_RETURN_IF_ERROR(fetch_typed(path.e[d].page_no, PageType::kInternal, &p));
    left_child = internal(p).child(path.e[d].index - 1);
  }
  return descend_edge(left_child, d + 1, true, &path, lf);
}

Status BTree::rank(uint64_t key, uint64_t* out) {
  bool present = false;
  return rank_exact(key, out, &present);
}

Status BTree::rank_exact(uint64_t key, uint64_t* rank, bool* present) {
  if (shards_) return shards_->rank_exact(key, rank, present);
  *rank = 0;
  *present = false;
  seal_tail();
  if (height_ == 0) return Status::Ok();
  uint32_t dir_leaf = 0, pos = 0;
  if (const std::byte* d = peek_plain_leaf(key, &dir_leaf)) {
    const page::LeafView v = leaf(d);
    const uint32_t n = page::count(d);
    pos = page::lower_bound(v.key_at(0), n, key);
    *rank = dir_->first_rank(dir_leaf) + pos;
    *present = pos < n && v.key(pos) == key;
    return Status::Ok();
  }
  PageRef lf;
  uint64_t before = 0, at = 0;
  WEAVER_RETURN_IF_ERROR(locate(key, false, &lf, &dir_leaf, &before));
  WEAVER_RETURN_IF_ERROR(leaf_bound(lf, key, false, &pos, nullptr, &at));
  *rank = before + pos;
  *present = pos < page::count(lf.data()) && at == key;
  return Status::Ok();
}

Status BTree::leaf_keys(uint64_t key, std::vector<uint64_t>* keys, uint64_t* first_rank,
                        std::vector<std::byte>* payloads) {
  if (shards_) return shards_->leaf_keys(key, keys, first_rank, payloads);
  keys->clear();
  if (payloads != nullptr) payloads->clear();
  *first_rank = 0;
  seal_tail();
  if (height_ == 0) return Status::Ok();
  PageRef lf;
  uint32_t dir_leaf = 0;
  WEAVER_RETURN_IF_ERROR(locate(key, true, &lf, &dir_leaf, first_rank));
  return leaf_entries(lf, keys, payloads);
}

Status BTree::select(uint64_t index, uint64_t* key_out, std::byte* payload_out) {
  if (shards_) return shards_->select(index, key_out, payload_out);
  seal_tail();
  if (index >= record_count_) {
    return Status::InvalidArgument(file_->name() + ": position " + std::to_string(index) +
                                   " is past the last record (" + std::to_string(record_count_) +
                                   " records)");
  }
  uint32_t pg = root_;
  for (uint32_t level = 0; level + 1 < height_; ++level) {
    PageRef p;
    WEAVER_RETURN_IF_ERROR(fetch_typed(pg, PageType::kInternal, &p));
    const uint32_t n = page::count(p.data());
    const page::InternalView v = internal(p);
    uint32_t i = 0;
    while (i + 1 < n && index >= v.subtree_count(i)) index -= v.subtree_count(i++);
    pg = v.child(i);
  }
  PageRef lf;
  WEAVER_RETURN_IF_ERROR(fetch_typed(pg, leaf_type(), &lf));
  if (index >= page::count(lf.data())) {
    return Status::Corruption(where(pg) + ": subtree counts disagree with leaf contents");
  }
  const auto i = static_cast<uint32_t>(index);
  WEAVER_RETURN_IF_ERROR(leaf_key(lf, i, key_out));
  if (payload_out != nullptr) return leaf_payload(lf, i, payload_out);
  return Status::Ok();
}

Status BTree::seek_keys(uint64_t key, BTreeCursor* c) { return position(key, true, c); }

Status BTree::seek_cursor(uint64_t key, BTreeCursor* c) { return position(key, false, c); }

Status BTree::position(uint64_t key, bool keys_only, BTreeCursor* c) {
  if (shards_) return shards_->position(key, keys_only, c);
  seal_tail();
  c->keys_only_ = keys_only;
  c->tree_ = this;
  c->valid_ = false;
  c->leaf_.reset();
  c->payload_ = payload_;
  if (height_ == 0) return Status::Ok();
  WEAVER_RETURN_IF_ERROR(descend(key, &c->path_, &c->leaf_));
  WEAVER_RETURN_IF_ERROR(c->load_leaf());
  c->i_ = page::lower_bound(reinterpret_cast<const std::byte*>(c->keys_), c->n_, key);
  return c->settle();
}

// Points keys_ and vals_ at the pinned leaf's entries: into the page for a
// plain leaf, into the cursor's buffers for a packed one, decoded whole.
Status BTreeCursor::load_leaf() {
  BTree& t = *tree_;
  n_ = page::count(leaf_.data());
  if (!t.options_.packed) {
    keys_ = reinterpret_cast<const uint64_t*>(leaf_.data() + page::kPageHeaderBytes);
    vals_ = leaf_.data() + page::kPageHeaderBytes + 8 * size_t{t.leaf_cap_};
    return Status::Ok();
  }
  if (kept_ != nullptr && !keys_only_) return load_kept();
  key_buf_.resize(n_);
  if (!keys_only_) val_buf_.resize(size_t{n_} * payload_);
  WEAVER_RETURN_IF_ERROR(decode_leaf(key_buf_.data(), keys_only_ ? nullptr : val_buf_.data()));
  keys_ = key_buf_.data();
  vals_ = keys_only_ ? nullptr : val_buf_.data();
  return Status::Ok();
}

Status BTreeCursor::decode_leaf(uint64_t* keys, std::byte* vals) {
  page::PackedLeaf reader;
  WEAVER_RETURN_IF_ERROR(tree_->open_packed(leaf_, &reader));
  if (!reader.decode(keys, vals)) {
    return Status::Corruption(tree_->where(leaf_.page_no()) + ": packed key block out of bounds");
  }
  return Status::Ok();
}

// The pinned leaf from the kept ones, else decoded into the buffers of the
// least recently loaded ones evicted to make room.
Status BTreeCursor::load_kept() {
  // A sharded table's leaves are its shards' pages: tree_ is the shard's.
  const std::string& file = tree_->file_name();
  const uint32_t page = leaf_.page_no();
  kept_leaf_ = kept_->find(file, page);
  if (kept_leaf_ == nullptr) {
    auto leaf = std::make_shared<DecodedLeaves::Leaf>(n_, payload_);
    WEAVER_RETURN_IF_ERROR(decode_leaf(leaf->keys.get(), leaf->vals.get()));
    kept_leaf_ = kept_->add(file, page, std::move(leaf));
  }
  keys_ = kept_leaf_->keys.get();
  vals_ = kept_leaf_->vals.get();
  return Status::Ok();
}

Status BTree::seek(uint64_t key, std::unique_ptr<Cursor>* out) {
  auto c = std::make_unique<BTreeCursor>();
  WEAVER_RETURN_IF_ERROR(seek_cursor(key, c.get()));
  *out = std::move(c);
  return Status::Ok();
}

Status BTreeCursor::settle() {
  if (i_ < n_) {
    valid_ = true;
    return Status::Ok();
  }
  return next_leaf();
}

Status BTreeCursor::next_leaf() {
  leaf_.recycle();
  valid_ = false;
  BTree& t = *tree_;
  for (int d = path_.depth - 1; d >= 0; --d) {
    PageRef p;
    WEAVER_RETURN_IF_ERROR(t.fetch_typed(path_.e[d].page_no, PageType::kInternal, &p));
    const uint32_t n = page::count(p.data());
    if (path_.e[d].index + 1 >= n) continue;
    const uint32_t child = t.internal(p).child(++path_.e[d].index);
    p.reset();
    WEAVER_RETURN_IF_ERROR(t.descend_edge(child, d + 1, false, &path_, &leaf_));
    WEAVER_RETURN_IF_ERROR(load_leaf());
    i_ = 0;
    valid_ = true;
    return Status::Ok();
  }
  // The end of a shard: on to the next one's first record.
  if (t.next_shard_ != nullptr) return t.next_shard_->position(0, keys_only_, this);
  return Status::Ok();
}

}  // namespace weaver
