// An in-memory directory of a B+tree's leaves, for point lookups in a tree
// that is not changing.
//
// A lookup through the tree searches one internal page per level, and each
// of those binary searches chases cache lines that the leaves' own traffic
// keeps evicting: at 10M records the internal levels cost about as much as
// the leaf.  The directory holds every leaf's fence (the smallest key the
// tree routes to it), page number and the rank of its first record, laid out
// for the cache: a top array of every 16th fence (a few KiB per GiB of tree,
// so it stays in the CPU cache) over chunks of 16 fences and page numbers,
// three cache lines each, asked for at once.  A lookup then pays about one
// cache miss before its leaf instead of one per probe of every level.
//
// The directory is a copy: the tree drops it on any change and rebuilds it
// from its internal pages (storage/btree_read.cc).
#pragma once

#include <cstdint>
#include <vector>

namespace weaver {

class LeafDirectory {
 public:
  static constexpr uint32_t kChunk = 16;

  // What a directory of `leaves` leaves takes in memory.
  static uint64_t bytes_for(uint64_t leaves);

  // Room for `leaves` leaves, so that adding them never holds two copies.
  void reserve(uint64_t leaves);
  // Adds the next leaf in key order.  The first fence must be 0 (every key
  // below the second fence goes to the first leaf); fences never decrease.
  void add(uint64_t fence, uint32_t page_no, uint64_t first_rank);
  // Frees everything: the directory is empty again.
  void clear();

  bool empty() const { return count_ == 0; }
  uint32_t size() const { return count_; }
  // REQUIRES: !empty().
  uint64_t last_fence() const { return chunks_.back().fence[(count_ - 1) % kChunk]; }
  // The leaf the tree routes `key` to: the last one whose fence is <= key.
  // REQUIRES: !empty().
  uint32_t find(uint64_t key) const;
  uint32_t page(uint32_t leaf) const { return chunks_[leaf / kChunk].page[leaf % kChunk]; }
  uint64_t first_rank(uint32_t leaf) const { return first_rank_[leaf]; }
  uint64_t fence(uint32_t leaf) const { return chunks_[leaf / kChunk].fence[leaf % kChunk]; }

 private:
  struct alignas(64) Chunk {
    uint64_t fence[kChunk];
    uint32_t page[kChunk];
  };
  std::vector<Chunk> chunks_;         // unused slots of the last: fence UINT64_MAX
  std::vector<uint64_t> top_;         // chunks_[c].fence[0]
  std::vector<uint64_t> first_rank_;  // per leaf
  uint32_t count_ = 0;
};

}  // namespace weaver
