// Per-table statistics for `weaver stat`.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "schema/status.h"
#include "storage/btree.h"

namespace weaver {

struct TableStats {
  std::string name;
  std::string file;
  KeyKind key_kind = KeyKind::kOctant;
  std::string schema;
  uint64_t records = 0;
  uint64_t file_bytes = 0;
  uint32_t page_size = 0;
  uint32_t payload_bytes = 0;
  uint32_t depth = 0;
  bool packed = false;                   // packed leaf pages (storage/packed_leaf.h)
  std::array<uint64_t, 21> per_level{};  // octant tables only
  std::array<uint64_t, 3> per_kind{};    // node tables: anchored, edge, face
  // What the metadata says of the mesh, as (name, text) lines: the model,
  // the ground and the rfile's PROJ string (octant table); the boundary's
  // kinds and least edge / vp (boundary table).
  std::vector<std::pair<std::string, std::string>> notes;

  // Raw size: an 8-byte key and the payload per record, nothing else.
  uint64_t raw_bytes() const { return records * (8 + uint64_t{payload_bytes}); }
  double bytes_per_record() const { return records ? double(file_bytes) / records : 0; }
  double overhead_pct() const {
    return records ? 100.0 * (double(file_bytes) / double(raw_bytes()) - 1) : 0;
  }
};

// Scans the table once (the level histogram needs every key).
Status table_stats(const std::string& name, BTree& table, TableStats* out);

std::string stats_to_text(const TableStats& s);
std::string stats_to_json(const TableStats& s);

}  // namespace weaver
