// Nodal pixels gathered by key, their masks ORed, then read back in key
// order: a bucket's (its workers') and the corners a bucket spills (its
// reader's).  Where every key lies in [base, bound] and less base is a
// multiple of 2^zeros, the offsets fit NodeWords (node_words.h), whose words
// are what the radix sort sorts; otherwise (spans wider than 55 bits) they
// are hashed by key (NodeHash) and sorted as records.
#pragma once

#include <bit>
#include <cstdint>
#include <vector>

#include "extract/node_hash.h"
#include "extract/node_words.h"
#include "extract/spill_store.h"

namespace weaver {

// Sorts records by key (a radix sort when their keys span few enough bits);
// packed and scratch are working buffers.
void sort_records(std::vector<SpillRecord>& records, std::vector<uint64_t>& packed,
                  std::vector<uint64_t>& scratch);

class NodePixels {
 public:
  // Empties it for about `expected` pixels whose keys lie in [base, bound]
  // and, less base, are multiples of 2^zeros.
  void reset(size_t expected, uint64_t base, int zeros, uint64_t bound) {
    base_ = base, zeros_ = zeros;
    fit_ = bound >= base && std::bit_width((bound - base) >> zeros) <= NodeWords::kOffsetBits;
    if (fit_) {
      words_.reset(expected);
    } else {
      hash_.reset(expected);
    }
  }

  // ORs mask into the key's, adding the key if new.
  void add(uint64_t key, uint8_t mask) {
    if (fit_) {
      words_.add((key - base_) >> zeros_, mask);
    } else {
      hash_.add(key, mask);
    }
  }

  size_t size() const { return fit_ ? words_.size() : hash_.size(); }

  // The pixels in key order, as f(view, count): view.key(i) and
  // view.mask(i) for i < count, valid until the next reset.  Returns what f
  // does.
  template <typename F>
  auto sorted(F&& f) {
    if (fit_) {
      sort_words();
      return f(Words{packed_.data(), base_, zeros_}, packed_.size());
    }
    sort_hashed();
    return f(Records{records_.data()}, records_.size());
  }

 private:
  struct Words {
    const uint64_t* w;
    uint64_t base;
    int zeros;
    uint64_t key(size_t i) const { return ((w[i] >> 8) << zeros) + base; }
    uint8_t mask(size_t i) const { return static_cast<uint8_t>(w[i]); }
  };
  struct Records {
    const SpillRecord* r;
    uint64_t key(size_t i) const { return r[i].key; }
    uint8_t mask(size_t i) const { return r[i].mask; }
  };
  void sort_words();
  void sort_hashed();

  NodeWords words_;
  NodeHash hash_;
  bool fit_ = false;
  uint64_t base_ = 0;
  int zeros_ = 0;
  std::vector<uint64_t> packed_, scratch_;
  std::vector<SpillRecord> records_;
};

}  // namespace weaver
