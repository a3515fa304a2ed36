#include "storage/decoded_leaves.h"

#include <algorithm>

namespace weaver {

// The page first: it tells most entries apart without reading a name.
DecodedLeaves::Kept* DecodedLeaves::lookup(const std::string& file, uint32_t page) {
  for (Kept& k : kept_) {
    if (k.page == page && k.file == file) return &k;
  }
  return nullptr;
}

std::shared_ptr<const DecodedLeaves::Leaf> DecodedLeaves::find(const std::string& file,
                                                               uint32_t page) {
  std::lock_guard<std::mutex> lock(mu_);
  Kept* k = lookup(file, page);
  if (k == nullptr) return nullptr;
  k->used = ++clock_;
  return k->leaf;
}

std::shared_ptr<const DecodedLeaves::Leaf> DecodedLeaves::add(const std::string& file,
                                                              uint32_t page,
                                                              std::shared_ptr<const Leaf> leaf) {
  std::lock_guard<std::mutex> lock(mu_);
  if (Kept* k = lookup(file, page)) {  // decoded by another thread meanwhile
    k->used = ++clock_;
    return k->leaf;
  }
  const size_t bytes = leaf->bytes();
  while (!kept_.empty() && bytes_ + bytes > budget_) {
    const auto lru = std::min_element(kept_.begin(), kept_.end(),
                                      [](const Kept& a, const Kept& b) { return a.used < b.used; });
    bytes_ -= lru->leaf->bytes();
    if (lru != kept_.end() - 1) *lru = std::move(kept_.back());
    kept_.pop_back();
  }
  bytes_ += bytes;
  kept_.push_back({file, page, ++clock_, std::move(leaf)});
  return kept_.back().leaf;
}

}  // namespace weaver
