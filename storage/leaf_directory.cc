#include "storage/leaf_directory.h"

#include <algorithm>

#include "storage/page_search.h"

namespace weaver {

uint64_t LeafDirectory::bytes_for(uint64_t leaves) {
  const uint64_t chunks = (leaves + kChunk - 1) / kChunk;
  return chunks * (sizeof(Chunk) + sizeof(uint64_t)) + leaves * sizeof(uint64_t);
}

void LeafDirectory::reserve(uint64_t leaves) {
  chunks_.reserve((leaves + kChunk - 1) / kChunk);
  top_.reserve((leaves + kChunk - 1) / kChunk);
  first_rank_.reserve(leaves);
}

void LeafDirectory::add(uint64_t fence, uint32_t page_no, uint64_t first_rank) {
  const uint32_t slot = count_ % kChunk;
  if (slot == 0) {
    chunks_.emplace_back();
    std::fill(std::begin(chunks_.back().fence), std::end(chunks_.back().fence), UINT64_MAX);
    std::fill(std::begin(chunks_.back().page), std::end(chunks_.back().page), 0u);
    top_.push_back(fence);
  }
  chunks_.back().fence[slot] = fence;
  chunks_.back().page[slot] = page_no;
  first_rank_.push_back(first_rank);
  ++count_;
}

void LeafDirectory::clear() {
  std::vector<Chunk>().swap(chunks_);
  std::vector<uint64_t>().swap(top_);
  std::vector<uint64_t>().swap(first_rank_);
  count_ = 0;
}

uint32_t LeafDirectory::find(uint64_t key) const {
  // top_[0] is 0, so the chunk is the last whose first fence is <= key.
  const auto* top = reinterpret_cast<const std::byte*>(top_.data());
  const uint32_t c = page::upper_bound(top, static_cast<uint32_t>(top_.size()), key) - 1;
  const Chunk& chunk = chunks_[c];
  // The chunk's three lines in flight together, not one after another.
  const auto* lines = reinterpret_cast<const char*>(&chunk);
  for (size_t off = 0; off < sizeof(Chunk); off += 64) __builtin_prefetch(lines + off);
  const auto* fences = reinterpret_cast<const std::byte*>(chunk.fence);
  const uint32_t i = page::upper_bound(fences, kChunk, key) - 1;
  // The padding's UINT64_MAX fences are <= key only when key is UINT64_MAX.
  return std::min(c * kChunk + i, count_ - 1);
}

}  // namespace weaver
