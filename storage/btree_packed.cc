// B+tree writes on packed leaves (storage/packed_leaf.h).  Appends go through
// the decoded tail (btree_insert.cc); a put or erase decodes the leaf it
// touches, edits the entries, and packs them back into as many pages as they
// need, hooking the new pages in like splits.
#include <algorithm>
#include <cstring>

#include "storage/btree.h"

namespace weaver {

using page::PageType;

// Rebuilds the decoded tail from the spine's (sealed) leaf.
Status BTree::load_tail() {
  std::vector<uint64_t> keys;
  std::vector<std::byte> vals;
  PageRef& lf = spine_[height_ - 1];
  WEAVER_RETURN_IF_ERROR(leaf_entries(lf, &keys, &vals));
  tail_->clear();
  tail_dirty_ = false;
  const auto n = static_cast<uint32_t>(keys.size());
  if (tail_->add_range(keys.data(), vals.data(), 0, n) != n) {
    return Status::Corruption(where(lf.page_no()) + ": packed leaf does not repack");
  }
  return Status::Ok();
}

// Splits entries into runs that each pack into one page: greedily, each page
// packed full; or, with `halve`, in two halves when both fit.  When they all
// fit one page, *edit_ holds them on return.
std::vector<std::pair<uint32_t, uint32_t>> BTree::pack_pieces(const std::vector<uint64_t>& keys,
                                                              const std::vector<std::byte>& vals,
                                                              bool halve) {
  const auto n = static_cast<uint32_t>(keys.size());
  page::PackedLeafBuilder& b = *edit_;
  auto fits = [&](uint32_t from, uint32_t to) {
    b.clear();
    return b.add_range(keys.data(), vals.data(), from, to);
  };
  if (fits(0, n) == n) return {{0, n}};
  if (halve && fits(0, n / 2) == n / 2 && fits(n / 2, n) == n) return {{0, n / 2}, {n / 2, n}};
  std::vector<std::pair<uint32_t, uint32_t>> pieces;
  for (uint32_t from = 0; from < n;) {
    const uint32_t to = std::max(fits(from, n), from + 1);  // one entry always fits
    pieces.emplace_back(from, to);
    from = to;
  }
  return pieces;
}

Status BTree::packed_write(std::byte* pg, const std::vector<uint64_t>& keys,
                           const std::vector<std::byte>& vals, uint32_t from, uint32_t to) {
  page::PackedLeafBuilder& b = *edit_;
  b.clear();
  if (b.add_range(keys.data(), vals.data(), from, to) != to) {
    return Status::Internal(file_->name() + ": a packed piece did not fit its page");
  }
  b.encode(pg);
  return Status::Ok();
}

// Writes the edited entries of s.leaf (now keys/vals, not empty) back: the
// leaf's path counts change by delta, and entries that no longer fit go to
// new right siblings.
Status BTree::packed_rewrite(LeafSlot& s, std::vector<uint64_t>& keys, std::vector<std::byte>& vals,
                             int64_t delta) {
  if (delta != 0) WEAVER_RETURN_IF_ERROR(add_to_path_counts(s.path, s.path.depth, delta));
  const bool at_end = s.pos >= s.n && path_is_rightmost(s.path);
  const auto pieces = pack_pieces(keys, vals, !at_end);
  if (pieces.size() == 1) {
    edit_->encode(s.leaf.data());
  } else {
    WEAVER_RETURN_IF_ERROR(
        packed_write(s.leaf.data(), keys, vals, pieces[0].first, pieces[0].second));
  }
  s.leaf.mark_dirty();
  s.leaf.reset();
  for (size_t j = 1; j < pieces.size(); ++j) {
    const uint64_t first = keys[pieces[j].first];
    uint64_t rest = keys.size() - pieces[j].first;
    Split split{first, rest, 0, pieces[j - 1].second - pieces[j - 1].first};
    {
      PageRef fresh;
      WEAVER_RETURN_IF_ERROR(new_page(leaf_type(), false, &fresh));
      WEAVER_RETURN_IF_ERROR(
          packed_write(fresh.data(), keys, vals, pieces[j].first, pieces[j].second));
      fresh.mark_dirty();
      split.page_no = fresh.page_no();
    }
    // The new page goes right after the one holding the previous piece,
    // which is where `first` routes until the new page is hooked in.
    Path path;
    PageRef lf;
    WEAVER_RETURN_IF_ERROR(descend(first, &path, &lf));
    lf.reset();
    WEAVER_RETURN_IF_ERROR(insert_into_parents(path, split, path_is_rightmost(path), 0));
  }
  return Status::Ok();
}

// put, or erase when `erase`, on a packed tree.
Status BTree::packed_edit(uint64_t key, const std::byte* payload, bool erase, bool* replaced) {
  if (replaced != nullptr) *replaced = false;
  drop_spine();
  if (height_ == 0) {
    if (erase) return Status::NotFound("key " + std::to_string(key));
    return insert_new_root_leaf(key, payload);
  }
  LeafSlot s;
  WEAVER_RETURN_IF_ERROR(find(key, &s));
  if (erase && !s.exact) return Status::NotFound("key " + std::to_string(key));
  std::vector<uint64_t> keys;
  std::vector<std::byte> vals;
  WEAVER_RETURN_IF_ERROR(leaf_entries(s.leaf, &keys, &vals));
  auto val = [&](uint32_t i) {
    return vals.begin() + static_cast<ptrdiff_t>(size_t{i} * payload_);
  };
  int64_t delta = 0;
  if (!erase && s.exact) {
    std::copy(payload, payload + payload_, val(s.pos));
    if (replaced != nullptr) *replaced = true;
  } else if (!erase) {
    keys.insert(keys.begin() + s.pos, key);
    vals.insert(val(s.pos), payload, payload + payload_);
    delta = 1;
    if (max_known_ && key > max_key_) max_key_ = key;
  } else {
    keys.erase(keys.begin() + s.pos);
    vals.erase(val(s.pos), val(s.pos + 1));
    delta = -1;
    if (max_known_ && key == max_key_) max_known_ = false;
  }
  record_count_ = static_cast<uint64_t>(static_cast<int64_t>(record_count_) + delta);
  if (!keys.empty()) return packed_rewrite(s, keys, vals, delta);
  // The leaf emptied: free it as a plain erase does.
  const uint32_t emptied = s.leaf.page_no();
  s.leaf.reset();
  WEAVER_RETURN_IF_ERROR(free_page(emptied));
  if (height_ == 1) {
    root_ = 0;
    height_ = 0;
    return Status::Ok();
  }
  return remove_empty_child(s.path, s.path.depth - 1);
}

}  // namespace weaver
