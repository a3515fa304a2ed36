// Decoded packed leaves kept for cursors that come back to them, shared by
// every cursor given the same DecodedLeaves, on any thread: a model
// database's readers (one a construct worker, each with its own handle of
// the one table) scan the same leaves, neighbouring subtrees' regions
// overlapping, and on two threads each decoded what the other had (2.3x
// the decodes of one thread).  Only for trees nobody writes while the
// cursors live.  Leaves are known by their file's name and page, so the
// handles of one table share them.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace weaver {

class DecodedLeaves {
 public:
  // n keys and their payloads, payload bytes each (left uninitialised
  // for the decoder to fill: zeroing them cost a fifth of a decode).
  struct Leaf {
    Leaf(uint32_t n, uint32_t payload)
        : keys(new uint64_t[n]),
          vals(new std::byte[size_t{n} * payload]),
          count(n),
          payload_bytes(payload) {}
    std::unique_ptr<uint64_t[]> keys;
    std::unique_ptr<std::byte[]> vals;
    uint32_t count;
    uint32_t payload_bytes;
    size_t bytes() const { return size_t{count} * (sizeof(uint64_t) + payload_bytes); }
  };
  // Keeps up to `budget` bytes of leaves (at least the last one added).
  explicit DecodedLeaves(size_t budget) : budget_(budget) {}

  // The leaf of page `page` of file `file`, if kept; null otherwise.
  std::shared_ptr<const Leaf> find(const std::string& file, uint32_t page);
  // Keeps `leaf` as page `page` of `file`, evicting the least recently
  // used past the budget; the leaf kept for it (another thread's, where
  // one added it first).  A cursor holding an evicted leaf keeps it alive.
  std::shared_ptr<const Leaf> add(const std::string& file, uint32_t page,
                                  std::shared_ptr<const Leaf> leaf);

 private:
  struct Kept {
    std::string file;
    uint32_t page = 0;
    uint64_t used = 0;  // clock_ when last found or added
    std::shared_ptr<const Leaf> leaf;
  };
  Kept* lookup(const std::string& file, uint32_t page);

  const size_t budget_;
  std::mutex mu_;
  std::vector<Kept> kept_;  // hundreds at most: searched in turn
  size_t bytes_ = 0;
  uint64_t clock_ = 0;
};

}  // namespace weaver
