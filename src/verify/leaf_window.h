// The last few leaf pages of a table, decoded, for verify's lookups (not
// query/leaf_window.h's LeafWindow, which serves batches of sorted keys).
//
// The mesh check asks, for every node, for the leaves around it and for the
// node's anchors: billions of floors and gets at 2 Hz, nearly all of them in
// a page it asked about a moment ago.  A B+tree lookup descends and decodes
// the packed page each time; here a page is decoded once and then answered
// by a binary search while it stays among the last few used.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "schema/status.h"
#include "storage/btree.h"

namespace weaver {

class RecentPages {
 public:
  // with_payloads: get() hands out payloads (floor() never does).
  RecentPages(BTree& table, bool with_payloads) : table_(table), payloads_(with_payloads) {}

  // The greatest key <= key, as BTree::floor.
  Status floor(uint64_t key, uint64_t* out, bool* found);
  // Whether key is in the table and, if so and with_payloads, where its
  // payload is (valid until the next call).
  Status get(uint64_t key, const std::byte** payload, bool* found);

 private:
  // One decoded leaf: its keys, and every key in [keys.front(), covers_to]
  // that is in the table is among them (the next leaf starts past covers_to).
  struct Page {
    std::vector<uint64_t> keys;
    std::vector<std::byte> payloads;
    uint64_t covers_to = 0;
    uint64_t used = 0;  // when last used, for replacement
  };
  static constexpr size_t kPages = 16;

  // The page that covers key, decoded from the tree if none does; null when
  // the key lies before the first key of its leaf (or the table is empty).
  Status page_for(uint64_t key, Page** page);

  BTree& table_;
  bool payloads_;
  std::array<Page, kPages> pages_;
  uint64_t clock_ = 0;
  size_t last_ = 0;  // the page used last: tried first
};

}  // namespace weaver
