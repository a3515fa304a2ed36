// On-disk format of a weaver B+tree file (all integers little-endian).
//
//   byte 0                4096           4096 + P        4096 + 2P
//   +--------------------+---------------+---------------+---- ...
//   | file header (4 KiB)|    page 1     |    page 2     |
//   +--------------------+---------------+---------------+---- ...
//
// Page n (n >= 1) starts at byte 4096 + (n - 1) * P, P the page size (a power
// of two, 128 .. 65536).  Page number 0 means "no page".
//
// File header (written last, at commit):
//   off size field
//   0   4    checksum32 of bytes [4, 4096)
//   4   4    format version (kFormatVersion)
//   8   8    magic "WVRBTREE"
//   16  4    page size P
//   20  4    payload size (bytes per record after the key)
//   24  1    key kind (0 = node key / plain u64, 1 = packed octant key)
//   25  1    leaf format (0 = plain, below; 1 = packed: storage/packed_leaf.h,
//            payloads column-wise; 2 = packed, each page's payloads
//            column-wise or as a row dictionary, whichever is smaller)
//   26  2    reserved, zero
//   28  4    tree height (0 = empty, 1 = the root is a leaf)
//   32  4    root page
//   36  4    page count (pages in use or free, excluding the header)
//   40  4    free-list head page (0 = none)
//   44  4    reserved, zero
//   48  8    record count
//   56  4    schema text length S
//   60  4    metadata length M
//   64  S    schema text (see schema/record_schema.h)
//   64+S M   metadata bytes (opaque to the tree; tables keep units here)
//
// Every page starts with a 16-byte header:
//   0   4    checksum32 of bytes [4, P)
//   4   4    page number (catches misdirected reads and writes)
//   8   1    page type: 1 leaf, 2 internal, 3 free, 4 packed leaf
//   9   1    format version
//   10  2    entry count n
//   12  4    free page: next free page; otherwise zero
//
// Leaf page, capacity L = (P - 16) / (8 + payload):
//   +--------+------------------------+----------------------------------+
//   | header | key[0..L) u64, sorted  | payload[0..L), `payload` bytes   |
//   +--------+------------------------+----------------------------------+
//   16       16 + 8L                   16 + (8 + payload) L
//   Keys are stored column-wise so a lookup binary-searches a dense array.
//
// Internal page, capacity I = (P - 16) / 20:
//   +--------+-----------------+-------------------+-------------------+
//   | header | key[0..I) u64   | count[0..I) u64   | child[0..I) u32   |
//   +--------+-----------------+-------------------+-------------------+
//   child[i] holds the keys k with key[i] <= k < key[i+1] (key[0] is not
//   used for routing); count[i] is the number of records under child[i],
//   which makes rank and select O(log n).
//
// Invariants (checked by BTree::check_invariants): keys strictly increase
// within and across leaves; every leaf is at depth height-1; no page but the
// root is empty; count[i] equals the records under child[i]; the header's
// record count equals the sum of the root's counts.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>

#include "schema/status.h"

namespace weaver::page {

inline constexpr uint32_t kFormatVersion = 1;  // do not change: on disk
inline constexpr char kMagic[8] = {'W', 'V', 'R', 'B', 'T', 'R', 'E', 'E'};
inline constexpr size_t kFileHeaderBytes = 4096;  // do not change: on disk
inline constexpr size_t kPageHeaderBytes = 16;    // do not change: on disk
inline constexpr uint32_t kMinPageSize = 128;     // keeps >= 5 entries per internal page
inline constexpr uint32_t kMaxPageSize = 65536;   // entry counts are u16

enum class PageType : uint8_t { kLeaf = 1, kInternal = 2, kFree = 3, kPackedLeaf = 4 };  // on disk

// File header field offsets.
inline constexpr size_t kHdrChecksum = 0, kHdrVersion = 4, kHdrMagic = 8, kHdrPageSize = 16,
                        kHdrPayloadSize = 20, kHdrKeyKind = 24, kHdrLeafFormat = 25,
                        kHdrHeight = 28, kHdrRoot = 32, kHdrPageCount = 36, kHdrFreeHead = 40,
                        kHdrRecordCount = 48, kHdrSchemaLen = 56, kHdrMetaLen = 60,
                        kHdrVarStart = 64;

// The file header's fields (the byte table at the top of this file).
struct FileHeader {
  uint32_t page_size = 0;
  uint32_t payload_size = 0;
  uint8_t key_kind = 0;     // KeyKind (storage/store.h): 0 or 1
  uint8_t leaf_format = 0;  // 0 plain, 1 packed (columns), 2 packed (columns or dictionary)
  uint32_t height = 0, root = 0, page_count = 0, free_head = 0;
  uint64_t record_count = 0;
  std::string schema_text;  // schema/record_schema.h's text form
  std::string metadata;
  friend bool operator==(const FileHeader&, const FileHeader&) = default;
};

// Whether the schema text and metadata fit in the header.
bool file_header_fits(size_t schema_bytes, size_t metadata_bytes);
// Writes h over out[0, kFileHeaderBytes), checksum last.
// REQUIRES: file_header_fits(h.schema_text.size(), h.metadata.size()).
void encode_file_header(const FileHeader& h, std::byte* out);
// Reads the header in in[0, kFileHeaderBytes).  Corruption, naming `name`,
// for a bad magic, checksum (where checksums are enforced), version, key
// kind, leaf format, or schema and metadata lengths.  The fields' meaning
// (page size, schema, tree shape) is for the reader to check.
Status decode_file_header(const std::byte* in, const std::string& name, FileHeader* h);

// Page header field offsets.
inline constexpr size_t kPgChecksum = 0, kPgNumber = 4, kPgType = 8, kPgVersion = 9, kPgCount = 10,
                        kPgNextFree = 12;

inline uint64_t load64(const std::byte* p) {
  uint64_t v;
  std::memcpy(&v, p, 8);
  return v;
}
inline uint32_t load32(const std::byte* p) {
  uint32_t v;
  std::memcpy(&v, p, 4);
  return v;
}
inline uint16_t load16(const std::byte* p) {
  uint16_t v;
  std::memcpy(&v, p, 2);
  return v;
}
inline void store64(std::byte* p, uint64_t v) { std::memcpy(p, &v, 8); }
inline void store32(std::byte* p, uint32_t v) { std::memcpy(p, &v, 4); }
inline void store16(std::byte* p, uint16_t v) { std::memcpy(p, &v, 2); }

inline uint64_t page_offset(uint32_t page_no, uint32_t page_size) {
  return kFileHeaderBytes + static_cast<uint64_t>(page_no - 1) * page_size;
}

inline uint32_t leaf_capacity(uint32_t page_size, uint32_t payload) {
  return static_cast<uint32_t>((page_size - kPageHeaderBytes) / (8 + payload));
}
inline uint32_t internal_capacity(uint32_t page_size) {
  return static_cast<uint32_t>((page_size - kPageHeaderBytes) / 20);
}

inline PageType type(const std::byte* pg) { return static_cast<PageType>(pg[kPgType]); }
inline uint32_t count(const std::byte* pg) { return load16(pg + kPgCount); }
inline void set_count(std::byte* pg, uint32_t n) {
  store16(pg + kPgCount, static_cast<uint16_t>(n));
}

// Typed views over a page in memory; `cap` is the page's capacity.
struct LeafView {
  std::byte* pg;
  uint32_t cap;
  uint32_t payload;
  std::byte* key_at(uint32_t i) const { return pg + kPageHeaderBytes + 8 * size_t{i}; }
  uint64_t key(uint32_t i) const { return load64(key_at(i)); }
  void set_key(uint32_t i, uint64_t k) const { store64(key_at(i), k); }
  std::byte* value(uint32_t i) const {
    return pg + kPageHeaderBytes + 8 * size_t{cap} + size_t{payload} * i;
  }
};

struct InternalView {
  std::byte* pg;
  uint32_t cap;
  std::byte* key_at(uint32_t i) const { return pg + kPageHeaderBytes + 8 * size_t{i}; }
  std::byte* count_at(uint32_t i) const {
    return pg + kPageHeaderBytes + 8 * size_t{cap} + 8 * size_t{i};
  }
  std::byte* child_at(uint32_t i) const {
    return pg + kPageHeaderBytes + 16 * size_t{cap} + 4 * size_t{i};
  }
  uint64_t key(uint32_t i) const { return load64(key_at(i)); }
  uint64_t subtree_count(uint32_t i) const { return load64(count_at(i)); }
  uint32_t child(uint32_t i) const { return load32(child_at(i)); }
  void set(uint32_t i, uint64_t key, uint64_t n, uint32_t child) const {
    store64(key_at(i), key);
    store64(count_at(i), n);
    store32(child_at(i), child);
  }
  void set_count(uint32_t i, uint64_t n) const { store64(count_at(i), n); }
};

}  // namespace weaver::page
