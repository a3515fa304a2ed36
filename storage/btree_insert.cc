// B+tree writes: random insert with in-place splits, and sorted append on
// the right spine.
#include <algorithm>
#include <cstring>
#include <vector>

#include "storage/btree.h"
#include "storage/page_search.h"

namespace weaver {

using page::PageType;

Status BTree::add_to_path_counts(const Path& path, int upto, int64_t delta) {
  for (int d = 0; d < upto; ++d) {
    PageRef p;
    WEAVER_RETURN_IF_ERROR(fetch_typed(path.e[d].page_no, PageType::kInternal, &p));
    const page::InternalView v = internal(p);
    const uint32_t i = path.e[d].index;
    v.set_count(i, v.subtree_count(i) + static_cast<uint64_t>(delta));
    p.mark_dirty();
  }
  return Status::Ok();
}

bool BTree::path_is_rightmost(const Path& path) {
  for (int d = 0; d < path.depth; ++d) {
    PageRef p;
    if (!fetch_typed(path.e[d].page_no, PageType::kInternal, &p).ok()) return false;
    if (path.e[d].index + 1 != page::count(p.data())) return false;
  }
  return true;
}

// Fills a fresh leaf with one entry.
Status BTree::init_leaf(PageRef& lf, uint64_t key, const std::byte* payload) {
  lf.mark_dirty();
  if (options_.packed) {
    tail_->clear();
    if (!tail_->add(key, payload)) return Status::Internal("packed leaf refused its first entry");
    tail_->encode(lf.data());
    return Status::Ok();
  }
  const page::LeafView v = leaf(lf);
  v.set_key(0, key);
  if (payload_ > 0) std::memcpy(v.value(0), payload, payload_);
  page::set_count(lf.data(), 1);
  return Status::Ok();
}

Status BTree::insert_new_root_leaf(uint64_t key, const std::byte* payload) {
  PageRef r;
  WEAVER_RETURN_IF_ERROR(new_page(leaf_type(), true, &r));
  WEAVER_RETURN_IF_ERROR(init_leaf(r, key, payload));
  root_ = r.page_no();
  height_ = 1;
  record_count_ = 1;
  max_known_ = true;
  max_key_ = key;
  return Status::Ok();
}

Status BTree::put(uint64_t key, const std::byte* payload, bool* replaced) {
  if (shards_) return sharded_write();
  changed();
  if (options_.packed) return packed_edit(key, payload, false, replaced);
  if (replaced != nullptr) *replaced = false;
  drop_spine();
  if (height_ == 0) return insert_new_root_leaf(key, payload);
  LeafSlot s;
  WEAVER_RETURN_IF_ERROR(find(key, &s));
  Path& path = s.path;
  PageRef& lf = s.leaf;
  const page::LeafView v = leaf(lf);
  const uint32_t n = s.n, pos = s.pos;
  if (s.exact) {
    if (payload_ > 0) std::memcpy(v.value(pos), payload, payload_);
    lf.mark_dirty();
    if (replaced != nullptr) *replaced = true;
    return Status::Ok();
  }
  if (max_known_ && key > max_key_) max_key_ = key;
  if (n < leaf_cap_) {
    std::memmove(v.key_at(pos + 1), v.key_at(pos), 8 * size_t{n - pos});
    std::memmove(v.value(pos + 1), v.value(pos), size_t{payload_} * (n - pos));
    v.set_key(pos, key);
    if (payload_ > 0) std::memcpy(v.value(pos), payload, payload_);
    page::set_count(lf.data(), n + 1);
    lf.mark_dirty();
    lf.reset();
    WEAVER_RETURN_IF_ERROR(add_to_path_counts(path, path.depth, 1));
    ++record_count_;
    return Status::Ok();
  }
  const bool rightmost = pos == n && path_is_rightmost(path);
  Split split;
  WEAVER_RETURN_IF_ERROR(split_leaf(lf, pos, key, payload, rightmost, &split));
  lf.reset();
  ++record_count_;
  return insert_into_parents(path, split, rightmost);
}

// Splits a full leaf while inserting (key, payload) at pos.  A split at the
// right end of the tree keeps the left page full (sequential inserts then
// pack pages the way append does); any other split halves the page.
Status BTree::split_leaf(PageRef& lf, uint32_t pos, uint64_t key, const std::byte* payload,
                         bool rightmost, Split* split) {
  const uint32_t n = page::count(lf.data());
  const uint32_t total = n + 1;
  const uint32_t left_n = rightmost ? n : total / 2;
  std::vector<uint64_t> keys(total);
  std::vector<std::byte> vals(size_t{total} * payload_);
  const page::LeafView v = leaf(lf);
  for (uint32_t i = 0, j = 0; i < total; ++i) {
    if (i == pos) {
      keys[i] = key;
      if (payload_ > 0) std::memcpy(vals.data() + size_t{i} * payload_, payload, payload_);
    } else {
      keys[i] = v.key(j);
      if (payload_ > 0) std::memcpy(vals.data() + size_t{i} * payload_, v.value(j), payload_);
      ++j;
    }
  }
  PageRef right;
  WEAVER_RETURN_IF_ERROR(new_page(PageType::kLeaf, false, &right));
  const page::LeafView rv = leaf(right);
  for (uint32_t i = 0; i < total; ++i) {
    const page::LeafView& dst = i < left_n ? v : rv;
    const uint32_t at = i < left_n ? i : i - left_n;
    dst.set_key(at, keys[i]);
    if (payload_ > 0) std::memcpy(dst.value(at), vals.data() + size_t{i} * payload_, payload_);
  }
  page::set_count(lf.data(), left_n);
  page::set_count(right.data(), total - left_n);
  lf.mark_dirty();
  right.mark_dirty();
  *split = Split{keys[left_n], total - left_n, right.page_no(), left_n};
  return Status::Ok();
}

Status BTree::insert_into_parents(Path& path, Split split, bool rightmost, int64_t above) {
  for (int d = path.depth - 1; d >= 0; --d) {
    PageRef p;
    WEAVER_RETURN_IF_ERROR(fetch_typed(path.e[d].page_no, PageType::kInternal, &p));
    const page::InternalView v = internal(p);
    const uint32_t n = page::count(p.data());
    const uint32_t idx = path.e[d].index;
    v.set_count(idx, split.left_count);
    const uint32_t pos = idx + 1;
    if (n < internal_cap_) {
      std::memmove(v.key_at(pos + 1), v.key_at(pos), 8 * size_t{n - pos});
      std::memmove(v.count_at(pos + 1), v.count_at(pos), 8 * size_t{n - pos});
      std::memmove(v.child_at(pos + 1), v.child_at(pos), 4 * size_t{n - pos});
      v.set(pos, split.key, split.count, split.page_no);
      page::set_count(p.data(), n + 1);
      p.mark_dirty();
      p.reset();
      return add_to_path_counts(path, d, above);
    }
    Split up;
    WEAVER_RETURN_IF_ERROR(split_internal(p, pos, split, rightmost, &up));
    split = up;
  }
  PageRef r;
  return grow_root(split, false, &r);
}

Status BTree::split_internal(PageRef& node, uint32_t pos, const Split& entry, bool rightmost,
                             Split* split) {
  struct Entry {
    uint64_t key, count;
    uint32_t child;
  };
  const page::InternalView v = internal(node);
  const uint32_t n = page::count(node.data());
  const uint32_t total = n + 1;
  std::vector<Entry> all(total);
  for (uint32_t i = 0, j = 0; i < total; ++i) {
    all[i] = i == pos ? Entry{entry.key, entry.count, entry.page_no}
                      : Entry{v.key(j), v.subtree_count(j), v.child(j++)};
  }
  const uint32_t left_n = rightmost ? n : total / 2;
  PageRef right;
  WEAVER_RETURN_IF_ERROR(new_page(PageType::kInternal, false, &right));
  const page::InternalView rv = internal(right);
  uint64_t left_sum = 0, right_sum = 0;
  for (uint32_t i = 0; i < total; ++i) {
    const Entry& e = all[i];
    if (i < left_n) {
      v.set(i, e.key, e.count, e.child);
      left_sum += e.count;
    } else {
      rv.set(i - left_n, e.key, e.count, e.child);
      right_sum += e.count;
    }
  }
  page::set_count(node.data(), left_n);
  page::set_count(right.data(), total - left_n);
  node.mark_dirty();
  right.mark_dirty();
  *split = Split{all[left_n].key, right_sum, right.page_no(), left_sum};
  return Status::Ok();
}

// A new root above the old one (holding split.left_count records) and its
// new right sibling; returned pinned in *root.
Status BTree::grow_root(const Split& split, bool at_end, PageRef* root) {
  if (height_ + 1 > kMaxHeight) return Status::IOError(file_->name() + ": tree too deep");
  uint64_t old_first_key;
  {
    PageRef old;
    WEAVER_RETURN_IF_ERROR(fetch(root_, &old));
    if (height_ == 1) {
      WEAVER_RETURN_IF_ERROR(leaf_key(old, 0, &old_first_key));
    } else {
      old_first_key = page::load64(old.data() + page::kPageHeaderBytes);
    }
  }
  WEAVER_RETURN_IF_ERROR(new_page(PageType::kInternal, at_end, root));
  const page::InternalView v = internal(*root);
  v.set(0, old_first_key, split.left_count, root_);
  v.set(1, split.key, split.count, split.page_no);
  page::set_count(root->data(), 2);
  root->mark_dirty();
  root_ = root->page_no();
  ++height_;
  return Status::Ok();
}

// ---------------------------------------------------------------------------
// Sorted append.  The right spine (root to rightmost leaf) stays pinned while
// appends run, so an append touches no page table and does no search.
// ---------------------------------------------------------------------------

void BTree::seal_tail() {
  if (!tail_dirty_) return;
  PageRef& lf = spine_[height_ - 1];
  tail_->encode(lf.data());
  lf.mark_dirty();
  tail_dirty_ = false;
}

void BTree::drop_spine() {
  seal_tail();
  for (PageRef& r : spine_) r.reset();
  spine_valid_ = false;
}

Status BTree::load_spine() {
  drop_spine();
  uint32_t pg = root_;
  for (uint32_t level = 0; level < height_; ++level) {
    const bool is_leaf = level + 1 == height_;
    WEAVER_RETURN_IF_ERROR(
        fetch_typed(pg, is_leaf ? leaf_type() : PageType::kInternal, &spine_[level]));
    const uint32_t n = page::count(spine_[level].data());
    if (n == 0) return Status::Corruption(where(pg) + ": empty page on the right spine");
    if (!is_leaf) pg = internal(spine_[level]).child(n - 1);
    if (is_leaf) WEAVER_RETURN_IF_ERROR(leaf_key(spine_[level], n - 1, &max_key_));
  }
  if (options_.packed) WEAVER_RETURN_IF_ERROR(load_tail());
  max_known_ = true;
  spine_valid_ = true;
  return Status::Ok();
}

// `delta` more records under the last entry of spine levels [0, levels).
void BTree::bump_spine_counts(int levels, uint64_t delta) {
  for (int d = 0; d < levels; ++d) {
    const page::InternalView iv = internal(spine_[d]);
    const uint32_t last = page::count(spine_[d].data()) - 1;
    iv.set_count(last, iv.subtree_count(last) + delta);
    spine_[d].mark_dirty();
  }
}

Status BTree::append_batch(const uint64_t* keys, const std::byte* payloads, size_t n) {
  if (shards_) return sharded_write();
  changed();
  if (n == 0) return Status::Ok();
  for (size_t i = 1; i < n; ++i) {
    if (keys[i] <= keys[i - 1]) {
      return Status::InvalidArgument(file_->name() + ": append out of order: key " +
                                     std::to_string(keys[i]) + " after key " +
                                     std::to_string(keys[i - 1]));
    }
  }
  WEAVER_RETURN_IF_ERROR(append(keys[0], payloads));  // checks keys[0] against the tree
  if (options_.packed) {
    // As many as the tail leaf takes at once, with one update of the spine's
    // counts; append() then seals the full tail and starts the next leaf.
    size_t i = 1;
    while (i < n) {
      if (!spine_valid_) WEAVER_RETURN_IF_ERROR(load_spine());  // e.g. after a new root leaf
      const uint32_t to =
          tail_->add_range(keys, payloads, static_cast<uint32_t>(i), static_cast<uint32_t>(n));
      if (to > i) {
        tail_dirty_ = true;
        bump_spine_counts(static_cast<int>(height_) - 1, to - i);
        record_count_ += to - i;
        max_key_ = keys[to - 1];
        i = to;
      }
      if (i < n) WEAVER_RETURN_IF_ERROR(append(keys[i], payloads + i * payload_));
      ++i;
    }
    return Status::Ok();
  }
  if (!spine_valid_) WEAVER_RETURN_IF_ERROR(load_spine());
  size_t i = 1;
  while (i < n) {
    PageRef& lf = spine_[height_ - 1];
    const uint32_t count = page::count(lf.data());
    const size_t room = leaf_cap_ - count;
    if (room == 0) {
      WEAVER_RETURN_IF_ERROR(append_new_leaf(keys[i], payloads + i * payload_));
      ++record_count_;
      ++i;
      continue;
    }
    const size_t k = std::min(room, n - i);
    const page::LeafView v = leaf(lf);
    std::memcpy(v.key_at(count), keys + i, 8 * k);
    if (payload_ > 0) std::memcpy(v.value(count), payloads + i * payload_, payload_ * k);
    page::set_count(lf.data(), static_cast<uint32_t>(count + k));
    lf.mark_dirty();
    bump_spine_counts(static_cast<int>(height_) - 1, k);
    record_count_ += k;
    i += k;
  }
  max_key_ = keys[n - 1];
  return Status::Ok();
}

Status BTree::append(uint64_t key, const std::byte* payload) {
  if (shards_) return sharded_write();
  changed();
  if (height_ == 0) return insert_new_root_leaf(key, payload);
  if (!spine_valid_) WEAVER_RETURN_IF_ERROR(load_spine());
  if (key <= max_key_) {
    return Status::InvalidArgument(file_->name() + ": append out of order: key " +
                                   std::to_string(key) + " after key " + std::to_string(max_key_));
  }
  PageRef& lf = spine_[height_ - 1];
  const uint32_t n = page::count(lf.data());
  if (options_.packed) {
    if (tail_->add(key, payload)) {
      tail_dirty_ = true;
      bump_spine_counts(static_cast<int>(height_) - 1);
    } else {
      seal_tail();
      WEAVER_RETURN_IF_ERROR(append_new_leaf(key, payload));
    }
  } else if (n < leaf_cap_) {
    const page::LeafView v = leaf(lf);
    v.set_key(n, key);
    if (payload_ > 0) std::memcpy(v.value(n), payload, payload_);
    page::set_count(lf.data(), n + 1);
    lf.mark_dirty();
    bump_spine_counts(static_cast<int>(height_) - 1);
  } else {
    WEAVER_RETURN_IF_ERROR(append_new_leaf(key, payload));
  }
  ++record_count_;
  max_key_ = key;
  return Status::Ok();
}

// The rightmost leaf is full: start a fresh one at the end of the file and
// hook it into the spine, adding fresh internal pages (and a new root) where
// the spine is full.  Nothing is split.
Status BTree::append_new_leaf(uint64_t key, const std::byte* payload) {
  PageRef fresh;
  WEAVER_RETURN_IF_ERROR(new_page(leaf_type(), true, &fresh));
  WEAVER_RETURN_IF_ERROR(init_leaf(fresh, key, payload));
  uint32_t entry_page = fresh.page_no();
  spine_[height_ - 1] = std::move(fresh);
  for (int d = static_cast<int>(height_) - 2; d >= 0; --d) {
    const uint32_t n = page::count(spine_[d].data());
    if (n < internal_cap_) {
      internal(spine_[d]).set(n, key, 1, entry_page);
      page::set_count(spine_[d].data(), n + 1);
      spine_[d].mark_dirty();
      bump_spine_counts(d);
      return Status::Ok();
    }
    PageRef up;
    WEAVER_RETURN_IF_ERROR(new_page(PageType::kInternal, true, &up));
    internal(up).set(0, key, 1, entry_page);
    page::set_count(up.data(), 1);
    up.mark_dirty();
    entry_page = up.page_no();
    spine_[d] = std::move(up);
  }
  // Every spine level was full: a new root above the old one.
  PageRef r;
  WEAVER_RETURN_IF_ERROR(grow_root(Split{key, 1, entry_page, record_count_}, true, &r));
  // grow_root raised height_: shift the old spine one level down.
  for (int d = static_cast<int>(height_) - 2; d >= 0; --d) spine_[d + 1] = std::move(spine_[d]);
  spine_[0] = std::move(r);
  return Status::Ok();
}

}  // namespace weaver
