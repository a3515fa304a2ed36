// A reader of the etree file format, the format of the original etree
// library (Tu & O'Hallaron; SCECcode/euclid-etree): SCEC's CVM etrees made by
// createcvm and UCVM's ucvm2etree, and the USGS San Francisco Bay Area model.
// Written from the format alone; no code of that library is in weaver.
//
// The file, as the library writes it (all integers in the byte order the
// file records, 'L' or 'B'):
//
//   offset  bytes  etree header (273 bytes)
//   0       1      byte order, 'L' or 'B'
//   1       4      format version (1)
//   5       4      dimensions (3; 4-D etrees are refused)
//   9       4      root level
//   13      4      application metadata size in bytes
//   17      256    leaf and interior octant counts, 2 x 4 bytes per level 0..31
//   273     33     B-tree header: byte order (1), page size (4), page count (8),
//                  root page number (8), key size (4), value size (4),
//                  ASCII schema size (4)
//   306     n      ASCII schema, NUL-terminated: "L 3 Vp float 4 0 Vs float 4 4 ..."
//                  (byte order, field count, then name type size offset per field)
//   P * k          page k (P the page size; pages start at the root page)
//   P * (root + count)   application metadata (its size from the etree header)
//
// A page:  0 right sibling page (8 bytes, -1 after the last leaf), 8 and 20:
// run-time fields of the library (garbage on disk), 16 entry count (4),
// 24 type 'l' (leaf) or 'i' (index), 25 entries.  A leaf entry is a key and a
// payload (value size bytes, the schema's fields packed at their offsets); an
// index entry is a key and a child page number (8 bytes), entry 0 the
// leftmost child.
//
// A 3-D key is 13 bytes: byte 0 the level (bits 0-6) and a leaf bit (0x80),
// bytes 1-12 the 96-bit Morton code of the octant's lower corner as a
// little-endian number whatever the file's byte order (bit 3i from x's bit i,
// 3i+1 from y, 3i+2 from z).  Keys order by Morton code then level, so an
// interior octant precedes its children.  The address space is 2^31 ticks a
// side: an octant of level l has edge 2^(31-l) ticks.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "schema/status.h"

namespace weaver {

inline constexpr int kEtreeMaxLevel = 31;  // do not change: on disk (32-bit ticks)

struct EtreeField {
  std::string name, type;
  uint32_t size = 0, offset = 0;
};

struct EtreeInfo {
  char byte_order = 'L';
  uint32_t page_size = 0;
  uint64_t page_count = 0, root_page = 0;
  uint32_t key_size = 0, value_size = 0;
  std::vector<EtreeField> fields;
  std::string app_metadata;            // as the producer wrote it
  uint64_t leaves = 0, interiors = 0;  // from the header's per-level counts
};

// One octant as the file holds it.
struct EtreeOctant {
  uint32_t x = 0, y = 0, z = 0;  // lower corner, in the file's 2^31 ticks
  int level = 0;
  bool leaf = true;
  const std::byte* payload = nullptr;  // value_size bytes, in the file's byte order
};

class EtreeFile {
 public:
  // Opens and checks the headers and schema.  Corruption naming the file
  // for anything that is not an etree file weaver can read.
  static Status open(const std::string& path, std::unique_ptr<EtreeFile>* out);
  ~EtreeFile();

  const EtreeInfo& info() const { return info_; }
  const std::string& path() const { return path_; }
  // The field named `name` (case-insensitive), or null.
  const EtreeField* field(const std::string& name) const;
  // A numeric field of a payload as a double, in this machine's byte order.
  double read_field(const std::byte* payload, const EtreeField& f) const;

  // Every octant in key order, through the chain of leaf pages.  Call
  // start() once, then next() until it sets *done.
  Status start();
  Status next(EtreeOctant* out, bool* done);

 private:
  explicit EtreeFile(std::string path) : path_(std::move(path)) {}
  Status read_headers();
  Status read_page(uint64_t page_no);
  uint64_t unsigned_at(const std::byte* p, int bytes) const;
  uint64_t u64(const std::byte* p) const { return unsigned_at(p, 8); }
  uint32_t u32(const std::byte* p) const { return static_cast<uint32_t>(unsigned_at(p, 4)); }
  Status bad(const std::string& why) const;

  std::string path_;
  int fd_ = -1;
  uint64_t file_bytes_ = 0;
  EtreeInfo info_;
  std::vector<std::byte> page_;
  uint64_t page_no_ = 0;
  uint32_t entry_ = 0, entries_ = 0;
  uint64_t pages_read_ = 0;
};

}  // namespace weaver
