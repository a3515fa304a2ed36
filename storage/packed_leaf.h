// Packed (compressed) B+tree leaves: keys delta-coded in blocks with a base
// key per block kept for binary search, payload fields stored column-wise,
// each with a frame of reference.  A table is packed or plain as a whole
// (file header byte 25); internal pages are the same in both.
//
// Packed leaf page (page type 4), all integers little-endian:
//
//   0        16    20         20+9F          20+9F+8m       20+9F+12m
//   +--------+-----+----------+--------------+--------------+-----------+--------------+---------+
//   | header | m F | field[F] | base[m] u64  | block[m] u32 | key bits  | column bits  | >= 16   |
//   +--------+-----+----------+--------------+--------------+-----------+--------------+ slack --+
//
//   header    the common 16-byte page header; its count is n, the entries.
//   m (u16)   blocks: entries [64j, 64j+64) form block j, so m = ceil(n/64).
//   F (u8)    the schema's field count.
//   coding (u8)   how the payloads are stored: 0 column-wise (below), 1 as a
//             row dictionary (below); files of leaf format 1 hold only 0.
//   field[f]  frame of reference of field f: min u64, width u8 (bits).
//             Entry i's field f is min + bits[i*width, (i+1)*width) of the
//             field's column, read as the field's raw little-endian bytes.
//   base[j]   the full key of block j's first entry (what lookups search).
//   block[j]  byte offset (u16, from the start of the key bits) | width u8 |
//             mode u8 (bit 7: octant successor model; bits 0-5: shift).
//             Entries 1..63 of the block are (cnt-1) residuals of `width`
//             bits each, from that byte offset:
//               mode 0 (delta):     key[i] = key[i-1] + ((r + 1) << shift)
//               mode 1 (successor): key[i] = subtree_end(key[i-1]) + r
//             In a linear octree the next leaf starts where the previous
//             one's subtree ends, so mode 1 leaves only the level slot (< 28,
//             5 bits); node keys of a mesh are near-dense after dropping the
//             block's common trailing zeros, so mode 0 leaves a few bits.
//   columns   coding 0: one bit column per field, each starting on a byte
//             boundary, right after the last block's key bits.
//             coding 1 (a row dictionary: the page's D distinct payloads,
//             where that is smaller; a mesh's materials in Z-order repeat
//             from leaf to leaf): field[0] holds min = D and width = w =
//             bit_width(D - 1), the other fields zero; then one column of n
//             w-bit indices, from a byte boundary, and after it (from the
//             next byte boundary) the D payloads, raw, in order of first use.
//   slack     the encoder leaves >= 16 bytes unused at the end, so readers
//             may load 64 bits at any bit offset inside the data.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "schema/record_schema.h"
#include "storage/store.h"

namespace weaver::page {

inline constexpr uint32_t kPackedBlock = 64;          // entries per block; do not change: on disk
inline constexpr uint32_t kPackedSlack = 16;          // unused tail bytes; do not change: on disk
inline constexpr uint32_t kPackedMaxEntries = 65535;  // the page header's count is a u16

// What a packed page needs to know of its table.
struct PackedShape {
  uint32_t page_size = 0;
  KeyKind key_kind = KeyKind::kNode;
  std::vector<uint32_t> field_sizes;  // bytes of each payload field, in record order
  uint32_t payload = 0;               // sum of field_sizes
  uint32_t uniform_field = 0;         // the size every field has (0: they differ)

  static PackedShape of(uint32_t page_size, KeyKind kind, const RecordSchema& schema);
  // Bytes from a packed page's start through its block table, for a page of
  // `entries` entries: what a point lookup reads before the one block it
  // decodes (and so what is worth prefetching for it).
  uint64_t index_bytes(uint64_t entries) const;
};

// Builds one packed leaf entry by entry, knowing at every step whether the
// next entry still fits the page.
class PackedLeafBuilder {
 public:
  explicit PackedLeafBuilder(const PackedShape& shape);

  // Adds (key, payload) if it fits; false (and no change) if it does not.
  // REQUIRES: key greater than every key added since clear().
  bool add(uint64_t key, const std::byte* payload);
  // Adds entries [from, to) of keys / vals (payloads packed row-wise) until
  // one does not fit; returns the index of the first one not added.
  uint32_t add_range(const uint64_t* keys, const std::byte* vals, uint32_t from, uint32_t to);
  // Writes the page body and the header's type and count (checksum and page
  // number are the buffer pool's).  REQUIRES: size() >= 1.
  void encode(std::byte* page) const;
  void clear();

  uint32_t size() const { return static_cast<uint32_t>(keys_.size()); }
  uint64_t key(uint32_t i) const { return keys_[i]; }
  const std::byte* payload(uint32_t i) const { return vals_.data() + size_t{i} * shape_.payload; }
  uint64_t encoded_bytes() const {
    return bytes_for(keys_.size(), key_bytes_closed_, open_, cols_, dict_first_.size());
  }

 private:
  struct OpenBlock {  // the residual widths each mode needs for the last block
    uint32_t count = 0;
    uint64_t base = 0, prev = 0;
    int shift = 63;             // mode 0: common trailing zeros of the deltas
    uint64_t max_delta = 0;     // mode 0
    bool successor_ok = true;   // mode 1: every key at or past its predecessor's subtree end
    uint64_t max_residual = 0;  // mode 1
  };
  struct Column {
    uint64_t min = UINT64_MAX, max = 0;
  };
  struct BlockCode {
    uint8_t width, mode;
  };
  // A distinct payload of the page: the first entry holding it, and its
  // place in the row dictionary.
  struct DictSlot {
    uint32_t first = UINT32_MAX, ordinal = 0;
  };

  // Adds all `count` entries if they fit together, else none.
  bool add_group(const uint64_t* keys, const std::byte* vals, uint32_t count);
  // Fields of one size, up to this many, take widen_columns' fast path.
  static constexpr size_t kMaxUniformFields = 8;
  void widen_columns(const std::byte* vals, uint32_t count);
  // Adds keys[0, count) to block b.  REQUIRES: b.count + count <= kPackedBlock.
  static void extend(OpenBlock& b, const uint64_t* keys, uint32_t count, KeyKind kind);
  static BlockCode choose(const OpenBlock& b, KeyKind kind);
  uint64_t bytes_for(size_t n, uint64_t key_bytes_closed, const OpenBlock& open,
                     const std::vector<Column>& cols, size_t dict_rows) const;
  // The payloads' bytes column-wise, and as a row dictionary (UINT64_MAX
  // when the page has too many distinct payloads for one).
  uint64_t column_bytes(size_t n, const std::vector<Column>& cols) const;
  uint64_t dictionary_bytes(size_t n, size_t dict_rows) const;
  // The slot of the row `payload`, or the empty slot where it would go.
  // Rows at entries >= keys_.size() are read from `group`.
  size_t dict_probe(const std::byte* payload, const std::byte* group) const;
  // Adds a group's rows to the dictionary (false: too many rows; it stops
  // tracking them); dict_added_ says which slots it filled.
  bool dict_add(const std::byte* vals, uint32_t count);
  void dict_rollback();
  void encode_dictionary(std::byte* page, std::byte* col) const;
  // Writes a field's column from n rows `stride` apart, its values `size`
  // bytes (1, 2, 4 or 8), less c.min, w bits each.
  static void put_column(const std::byte* p, size_t stride, uint32_t n, uint32_t size,
                         const Column& c, uint32_t w, std::byte* out);

  PackedShape shape_;
  std::vector<uint64_t> keys_;
  std::vector<std::byte> vals_;
  std::vector<BlockCode> closed_;  // codes of the full blocks
  uint64_t key_bytes_closed_ = 0;  // key bits of the full blocks, each rounded up to a byte
  OpenBlock open_;
  std::vector<Column> cols_;
  std::vector<Column> scratch_cols_;
  std::vector<DictSlot> dict_slots_;  // open addressing by a hash of the row
  std::vector<uint32_t> dict_first_;  // by ordinal: the first entry holding the row
  std::vector<size_t> dict_added_;    // slots filled by the group being added
  // By entry: its row's ordinal (while the dictionary is kept), so that
  // encoding writes them without probing the rows again.
  std::vector<uint32_t> dict_ordinal_;
  size_t dict_max_rows_ = 0;  // past this, no dictionary can beat the columns
  bool dict_over_ = false;    // the page has more distinct rows than that
};

// Read access to a packed leaf in a page.  Every accessor checks the offsets
// it follows against the page, so a damaged page reads as corrupt, never out
// of bounds.
class PackedLeaf {
 public:
  // False if the page's layout fields do not fit the page.
  bool open(const std::byte* page, const PackedShape& shape);

  uint32_t size() const { return n_; }
  // Decodes the keys of entries [64j, 64j+cnt) into out (up to 64); false if damaged.
  bool block_keys(uint32_t j, uint64_t* out, uint32_t* cnt) const;
  // The first i with key(i) >= k (or > k when `upper`), or size(); and, from
  // the same block decode, the keys either side of it: *below = key(i - 1)
  // when i > 0, *at = key(i) when i < size() (either may be null).  With
  // payload_next (the caller reads a payload next), the payload lines of the
  // block searched are asked for while its keys decode.
  bool bound(uint64_t k, bool upper, uint32_t* pos, uint64_t* below = nullptr,
             uint64_t* at = nullptr, bool payload_next = false) const;
  bool key(uint32_t i, uint64_t* out) const;
  // The block holding the last key <= k, decoded into keys (*cnt of them,
  // up to kPackedBlock), and *limit, the next block's first key (0 past the
  // page's last block: the next key is another page's).  *cnt is 0 when
  // every key of the page is > k.  False if damaged.
  bool floor_block(uint64_t k, uint64_t* keys, uint32_t* cnt, uint64_t* limit) const;
  // Prefetches block j's payload bits in every column.
  void prefetch_payloads(uint32_t j) const;
  // Writes entry i's payload (shape.payload bytes).
  void payload(uint32_t i, std::byte* out) const;
  // Decodes everything: keys into keys[0..n), payloads packed row-wise
  // (skipped when vals is null).
  bool decode(uint64_t* keys, std::byte* vals) const;

 private:
  // Block j's key bits, entry count, residual width and mode; null if the
  // block's bits lie outside the page.
  const std::byte* block_bits(uint32_t j, uint32_t* cnt, uint32_t* w, uint8_t* mode) const;
  bool open_dictionary(uint64_t col, uint64_t limit);
  const std::byte* dict_row(uint32_t i) const;
  template <uint32_t Size>
  bool decode_dictionary(std::byte* vals) const;

  const std::byte* pg_ = nullptr;
  const PackedShape* shape_ = nullptr;
  uint32_t n_ = 0, m_ = 0;
  const std::byte* fields_ = nullptr;
  const std::byte* bases_ = nullptr;
  const std::byte* blocks_ = nullptr;
  const std::byte* key_bits_ = nullptr;
  const std::byte* end_ = nullptr;  // the first byte the data may not reach
  std::vector<const std::byte*> cols_;
  // Coding 1: the index column, the dictionary's rows, their count and the
  // indices' width.
  const std::byte* dict_index_ = nullptr;
  const std::byte* dict_rows_ = nullptr;
  uint64_t dict_count_ = 0;
  uint32_t dict_width_ = 0;
};

}  // namespace weaver::page
