// B+tree deletes.  A leaf that becomes empty is freed and unhooked from its
// parent (recursively); half-empty pages are not merged, which keeps deletes
// local.  A root with a single child is collapsed.
#include <cstring>

#include "storage/btree.h"
#include "storage/page_search.h"

namespace weaver {

using page::PageType;

Status BTree::erase(uint64_t key) {
  if (shards_) return sharded_write();
  changed();
  if (options_.packed) return packed_edit(key, nullptr, true, nullptr);
  drop_spine();
  if (height_ == 0) return Status::NotFound("key " + std::to_string(key));
  LeafSlot s;
  WEAVER_RETURN_IF_ERROR(find(key, &s));
  if (!s.exact) return Status::NotFound("key " + std::to_string(key));
  Path& path = s.path;
  PageRef& lf = s.leaf;
  const page::LeafView v = leaf(lf);
  const uint32_t n = s.n, pos = s.pos;
  std::memmove(v.key_at(pos), v.key_at(pos + 1), 8 * size_t{n - pos - 1});
  std::memmove(v.value(pos), v.value(pos + 1), size_t{payload_} * (n - pos - 1));
  page::set_count(lf.data(), n - 1);
  lf.mark_dirty();
  --record_count_;
  if (max_known_ && key == max_key_) max_known_ = false;
  if (n - 1 > 0 || height_ == 1) {
    lf.reset();
    if (height_ == 1 && n - 1 == 0) {  // the tree is now empty
      WEAVER_RETURN_IF_ERROR(free_page(root_));
      root_ = 0;
      height_ = 0;
      return Status::Ok();
    }
    return add_to_path_counts(path, path.depth, -1);
  }
  const uint32_t emptied = lf.page_no();
  lf.reset();
  WEAVER_RETURN_IF_ERROR(free_page(emptied));
  return remove_empty_child(path, path.depth - 1);
}

// The child at path.e[level] was freed: drop its entry, freeing pages that
// become empty on the way up, then fix counts above and collapse the root.
Status BTree::remove_empty_child(Path& path, int level) {
  for (int d = level; d >= 0; --d) {
    PageRef p;
    WEAVER_RETURN_IF_ERROR(fetch_typed(path.e[d].page_no, PageType::kInternal, &p));
    const page::InternalView v = internal(p);
    const uint32_t n = page::count(p.data());
    const uint32_t idx = path.e[d].index;
    std::memmove(v.key_at(idx), v.key_at(idx + 1), 8 * size_t{n - idx - 1});
    std::memmove(v.count_at(idx), v.count_at(idx + 1), 8 * size_t{n - idx - 1});
    std::memmove(v.child_at(idx), v.child_at(idx + 1), 4 * size_t{n - idx - 1});
    page::set_count(p.data(), n - 1);
    p.mark_dirty();
    if (n - 1 > 0) {
      p.reset();
      WEAVER_RETURN_IF_ERROR(add_to_path_counts(path, d, -1));
      return collapse_root();
    }
    const uint32_t emptied = p.page_no();
    p.reset();
    WEAVER_RETURN_IF_ERROR(free_page(emptied));
    if (d == 0) {  // the root emptied: so did the tree
      root_ = 0;
      height_ = 0;
      return Status::Ok();
    }
  }
  return Status::Ok();
}

Status BTree::collapse_root() {
  while (height_ > 1) {
    uint32_t only_child;
    {
      PageRef r;
      WEAVER_RETURN_IF_ERROR(fetch_typed(root_, PageType::kInternal, &r));
      if (page::count(r.data()) != 1) return Status::Ok();
      only_child = internal(r).child(0);
    }
    WEAVER_RETURN_IF_ERROR(free_page(root_));
    root_ = only_child;
    --height_;
  }
  return Status::Ok();
}

}  // namespace weaver
