// BTree::check_invariants: a full walk that verifies the invariants listed in
// page_format.h and names the first page that breaks one.
#include <vector>

#include "storage/btree.h"
#include "storage/shard_set.h"

namespace weaver {

using page::PageType;

Status BTree::check_invariants() {
  if (shards_) return shards_->check_invariants();
  seal_tail();
  if (height_ == 0) {
    if (record_count_ != 0) return Status::Corruption(file_->name() + ": empty tree has records");
    return Status::Ok();
  }
  uint64_t count = 0, first = 0, last = 0;
  WEAVER_RETURN_IF_ERROR(check_subtree(root_, 0, 0, UINT64_MAX, &count, &first, &last));
  if (count != record_count_) {
    return Status::Corruption(file_->name() + ": header says " + std::to_string(record_count_) +
                              " records, tree holds " + std::to_string(count));
  }
  return Status::Ok();
}

// Keys under page_no must lie in [lo, hi]; reports the count and key span.
Status BTree::check_subtree(uint32_t page_no, int level, uint64_t lo, uint64_t hi, uint64_t* count,
                            uint64_t* first_key, uint64_t* last_key) {
  const bool is_leaf = static_cast<uint32_t>(level) + 1 == height_;
  PageRef p;
  WEAVER_RETURN_IF_ERROR(fetch_typed(page_no, is_leaf ? leaf_type() : PageType::kInternal, &p));
  const uint32_t n = page::count(p.data());
  const uint32_t leaf_cap = options_.packed ? page::kPackedMaxEntries : leaf_cap_;
  const uint32_t cap = is_leaf ? leaf_cap : internal_cap_;
  if (n == 0 || n > cap) {
    return Status::Corruption(where(page_no) + ": entry count " + std::to_string(n) +
                              " outside [1, " + std::to_string(cap) + "]");
  }
  if (is_leaf) {
    std::vector<uint64_t> keys;
    WEAVER_RETURN_IF_ERROR(leaf_entries(p, &keys, nullptr));
    for (uint32_t i = 0; i < n; ++i) {
      const uint64_t k = keys[i];
      if (k < lo || k > hi || (i > 0 && k <= keys[i - 1])) {
        return Status::Corruption(where(page_no) + ": key " + std::to_string(k) + " at slot " +
                                  std::to_string(i) + " is out of order");
      }
    }
    *count = n;
    *first_key = keys[0];
    *last_key = keys[n - 1];
    return Status::Ok();
  }
  const page::InternalView v = internal(p);
  uint64_t total = 0;
  for (uint32_t i = 0; i < n; ++i) {
    const uint64_t sub_lo = i == 0 ? lo : v.key(i);
    const uint64_t sub_hi = i + 1 < n ? v.key(i + 1) - 1 : hi;
    // key[0] routes nothing and may be stale; separators from key[1] on must
    // increase and stay within the parent's bounds.
    if ((i > 1 && v.key(i) <= v.key(i - 1)) || (i > 0 && (v.key(i) < lo || v.key(i) > hi))) {
      return Status::Corruption(where(page_no) + ": separator " + std::to_string(i) +
                                " is out of order");
    }
    uint64_t c = 0, f = 0, l = 0;
    WEAVER_RETURN_IF_ERROR(check_subtree(v.child(i), level + 1, sub_lo, sub_hi, &c, &f, &l));
    if (c != v.subtree_count(i)) {
      return Status::Corruption(where(page_no) + ": entry " + std::to_string(i) + " counts " +
                                std::to_string(v.subtree_count(i)) + " records, child holds " +
                                std::to_string(c));
    }
    if (i == 0) *first_key = f;
    *last_key = l;
    total += c;
  }
  *count = total;
  return Status::Ok();
}

}  // namespace weaver
