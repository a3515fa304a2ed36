// Lookups in a table answered from its last few decoded leaf pages: the one
// window over an octant or node table that queries, slices and verify ask.
//
// Their lookups come in Z-order or close to it: a batch of points sorted by
// Morton code, a slice's leaves along a plane, verify's leaves around each
// node and its anchors.  Nearly every key lands in a page asked about a
// moment ago.  A B+tree lookup descends and decodes the packed page each
// time; here a page is decoded once and then answered by a binary search
// while it stays among the last few used.  Keys in any order are still
// answered correctly.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "schema/status.h"
#include "storage/btree.h"

namespace weaver {

class LeafWindow {
 public:
  // with_payloads: floor() and get() hand out payloads.
  LeafWindow(BTree& table, bool with_payloads) : table_(table), payloads_(with_payloads) {}

  struct Floor {
    bool found = false;  // false: no key <= the one asked
    uint64_t key = 0;
    uint64_t rank = 0;                   // the number of keys < key
    const std::byte* payload = nullptr;  // valid until the next call
  };
  // The greatest key <= key, its rank and (with payloads) its payload.
  Status floor(uint64_t key, Floor* out);
  // Whether key is in the table and, if so and with payloads, where its
  // payload is (valid until the next call).
  Status get(uint64_t key, const std::byte** payload, bool* found);
  // Sparse: answer each floor (and get) by its own descent, without
  // decoding whole leaves.  For a few keys (one question) that is cheaper;
  // for a batch that lands many keys in each leaf, the decoded leaf is.
  // recycle_leaves: a large batch proven sparse, whose leaves are read once
  // each, offers them to the pool as its next victims (it would otherwise
  // fill every frame with pages it will not ask again); a few questions keep
  // theirs, for the next few (a server's requests) to find.
  void set_sparse(bool sparse, bool recycle_leaves = false) {
    sparse_ = sparse;
    recycle_ = sparse && recycle_leaves;
  }
  bool sparse() const { return sparse_; }
  // Leaf pages decoded so far: with the keys asked, how dense a batch is.
  uint64_t decodes() const { return decodes_; }

 private:
  // One decoded leaf: its keys, and every key in [keys.front(), covers_to]
  // that is in the table is among them (the next leaf starts past covers_to).
  struct Page {
    std::vector<uint64_t> keys;
    std::vector<std::byte> payloads;
    uint64_t first_rank = 0;  // the rank of keys.front()
    uint64_t covers_to = 0;
    uint64_t used = 0;  // when last used, for replacement
  };
  static constexpr size_t kPages = 16;

  // The page that covers key, decoded from the tree if none does; null when
  // the key lies before the first key of its leaf (or the table is empty),
  // and then *leaf_rank is the rank of that leaf's first key.
  Status page_for(uint64_t key, Page** page, uint64_t* leaf_rank);
  Status sparse_floor(uint64_t key, Floor* out);

  BTree& table_;
  bool payloads_;
  bool sparse_ = false;
  bool recycle_ = false;
  std::array<Page, kPages> pages_;
  uint64_t clock_ = 0;
  size_t last_ = 0;  // the page used last: tried first
  uint64_t decodes_ = 0;
  std::vector<std::byte> single_;  // a payload read outside the pages
};

}  // namespace weaver
