#include "query/table_stats.h"

#include <cstdio>
#include <cstdlib>

#include "db/aggregate_table.h"
#include "db/boundary_table.h"
#include "db/octant_table.h"
#include "schema/node.h"
#include "schema/octant.h"
#include "util/json_string.h"
#include "util/metadata_text.h"

namespace weaver {
Status table_stats(const std::string& name, BTree& table, TableStats* out) {
  TableStats s;
  s.name = name;
  s.file = table.file_name();
  s.key_kind = table.options().key_kind;
  s.schema = table.options().schema.to_text();
  s.records = table.size();
  s.file_bytes = table.file_bytes();
  s.page_size = table.options().page_size;
  s.payload_bytes = table.payload_size();
  s.depth = table.height();
  s.packed = table.options().packed;
  const Field* kind = table.options().schema.find("kind");
  const std::string& meta = table.options().metadata;
  if (name == kBoundaryTable) {
    s.notes = {{"free surface", metadata_item(meta, "free_surface")},
               {"domain sides", metadata_item(meta, "sides")}};
    const double dt = std::strtod(metadata_item(meta, "least_dt").c_str(), nullptr);
    if (dt > 0) {
      char buf[160];
      std::snprintf(buf, sizeof buf,
                    "%.6g s at element %s (an explicit solver's step: a Courant number times it)",
                    dt, metadata_item(meta, "least_dt_element").c_str());
      s.notes.push_back({"least edge/vp", buf});
    }
    kind = nullptr;
  }
  if (name == kOctantTable) {
    for (const char* key :
         {"tick_m", "origin_m", "geo", "model", "surface", "top_elevation_m", "model_z", "proj"}) {
      const std::string v = metadata_item(meta, key);
      if (!v.empty()) s.notes.push_back({key, v});
    }
  }
  if (s.key_kind == KeyKind::kNode && kind != nullptr) {
    BTreeCursor c;
    WEAVER_RETURN_IF_ERROR(table.seek_cursor(0, &c));
    while (c.valid()) {
      const uint64_t k = RecordSchema::get_uint(c.payload(), *kind);
      if (k > 2) return Status::Corruption(s.file + ": bad node kind " + std::to_string(k));
      ++s.per_kind[k];
      WEAVER_RETURN_IF_ERROR(c.next());
    }
  }
  const bool counted =  // by the table's writer, into its metadata
      s.key_kind == KeyKind::kOctant &&
      levels_from_metadata(table.options().metadata, &s.per_level);
  if (s.key_kind == KeyKind::kOctant && !counted) {
    BTreeCursor c;
    WEAVER_RETURN_IF_ERROR(table.seek_cursor(0, &c));
    while (c.valid()) {
      if (!octant_key_is_valid(c.key())) {
        return Status::Corruption(s.file + ": invalid octant key " + std::to_string(c.key()));
      }
      ++s.per_level[octant_from_key(c.key()).level];
      WEAVER_RETURN_IF_ERROR(c.next());
    }
  }
  *out = s;
  return Status::Ok();
}

std::string stats_to_text(const TableStats& s) {
  char buf[512];
  std::string out;
  std::snprintf(buf, sizeof buf,
                "table %s (%s)\n  records          %llu\n  bytes on disk    %llu\n"
                "  bytes per record %.3f (raw %u: 8-byte key + %u-byte payload)\n"
                "  size vs raw      %.2f%%\n  leaf pages       %s\n  tree depth       %u\n"
                "  page size        %u\n  payload schema   %s\n",
                s.name.c_str(), s.file.c_str(), (unsigned long long)s.records,
                (unsigned long long)s.file_bytes, s.bytes_per_record(), 8 + s.payload_bytes,
                s.payload_bytes, 100 + s.overhead_pct(), s.packed ? "packed" : "plain", s.depth,
                s.page_size, s.schema.empty() ? "(none)" : s.schema.c_str());
  out += buf;
  if (s.key_kind == KeyKind::kOctant) {
    out += s.name == kAggregateTable ? "  octants summarised per level\n" : "  leaves per level\n";
    for (int l = 0; l <= 20; ++l) {
      if (s.per_level[l] == 0) continue;
      std::snprintf(buf, sizeof buf, "    level %2d  %llu\n", l,
                    (unsigned long long)s.per_level[l]);
      out += buf;
    }
  }
  for (const auto& [k, v] : s.notes) {
    std::snprintf(buf, sizeof buf, "  %-16s ", k.c_str());
    out += buf + v + "\n";
  }
  if (s.key_kind == KeyKind::kNode && s.name != kBoundaryTable) {
    std::snprintf(buf, sizeof buf,
                  "  anchored         %llu\n  edge-dangling    %llu\n  face-dangling    %llu\n",
                  (unsigned long long)s.per_kind[0], (unsigned long long)s.per_kind[1],
                  (unsigned long long)s.per_kind[2]);
    out += buf;
  }
  return out;
}

std::string stats_to_json(const TableStats& s) {
  char buf[512];
  std::snprintf(buf, sizeof buf,
                ", \"records\": %llu, \"bytes\": %llu, "
                "\"bytes_per_record\": %.4f, \"raw_bytes_per_record\": %u, "
                "\"overhead_pct\": %.4f, \"packed\": %s, \"depth\": %u, \"page_size\": %u, "
                "\"schema\": ",
                (unsigned long long)s.records, (unsigned long long)s.file_bytes,
                s.bytes_per_record(), 8 + s.payload_bytes, s.overhead_pct(),
                s.packed ? "true" : "false", s.depth, s.page_size);
  std::string out = "{\"table\": " + json_string(s.name) + ", \"file\": " + json_string(s.file) +
                    buf + json_string(s.schema);
  if (s.key_kind == KeyKind::kOctant) {
    out += ", \"per_level\": {";
    bool first = true;
    for (int l = 0; l <= 20; ++l) {
      if (s.per_level[l] == 0) continue;
      out += (first ? "\"" : ", \"") + std::to_string(l) + "\": " + std::to_string(s.per_level[l]);
      first = false;
    }
    out += "}";
  }
  for (const auto& [k, v] : s.notes) out += ", " + json_string(k) + ": " + json_string(v);
  if (s.key_kind == KeyKind::kNode && s.name != kBoundaryTable) {
    out += ", \"anchored\": " + std::to_string(s.per_kind[0]) +
           ", \"edge_dangling\": " + std::to_string(s.per_kind[1]) +
           ", \"face_dangling\": " + std::to_string(s.per_kind[2]);
  }
  return out + "}";
}

}  // namespace weaver
