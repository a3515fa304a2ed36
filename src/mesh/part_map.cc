#include "mesh/part_map.h"

#include <algorithm>
#include <cstring>

namespace weaver {

PartMap PartMap::of_runs(std::vector<PartRun> runs, uint32_t parts) {
  PartMap m;
  m.runs_ = std::move(runs);
  m.parts_ = parts;
  return m;
}

Status PartMap::of_table(BTree& table, uint32_t parts, PartMap* out) {
  if (table.payload_size() != 4) {
    return Status::Corruption(table.file_name() + ": not a partition table (payload of " +
                              std::to_string(table.payload_size()) + " bytes)");
  }
  *out = PartMap();
  out->table_ = &table;
  out->parts_ = parts;
  return Status::Ok();
}

Status PartMap::part_of(uint64_t id, uint32_t* part) const {
  if (table_ == nullptr) {
    const auto it = std::upper_bound(runs_.begin(), runs_.end(), id,
                                     [](uint64_t v, const PartRun& r) { return v < r.first; });
    if (it == runs_.begin()) return Status::Internal("no part run starts at element 0");
    *part = std::prev(it)->part;
    return Status::Ok();
  }
  uint64_t key = 0;
  std::byte payload[4];
  bool found = false;
  WEAVER_RETURN_IF_ERROR(table_->floor(id, &key, payload, &found));
  if (!found) return Status::Corruption(table_->file_name() + ": no run starts at element 0");
  std::memcpy(part, payload, 4);
  if (*part >= parts_) {
    return Status::Corruption(table_->file_name() + ": part " + std::to_string(*part) +
                              " of element " + std::to_string(id) + " is not below " +
                              std::to_string(parts_));
  }
  return Status::Ok();
}

}  // namespace weaver
