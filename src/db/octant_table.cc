#include "db/octant_table.h"

#include <cstdio>
#include <sstream>

#include "storage/btree.h"

namespace weaver {

Status floor_holding(BTree& table, const Octant& o, uint64_t* key, std::byte* payload,
                     bool* found) {
  WEAVER_RETURN_IF_ERROR(table.floor(octant_key(o), key, payload, found));
  *found = *found && key_holds(*key, o);
  return Status::Ok();
}

namespace {

// Whether leaves a and b are siblings: children of one parent.
bool octant_keys_are_siblings(uint64_t a, uint64_t b) {
  const int level = octant_key_level(a);
  if (level == 0 || level != octant_key_level(b)) return false;
  const int parent_bits = 3 * (kMaxLevel - level + 1);
  return octant_key_morton(a) >> parent_bits == octant_key_morton(b) >> parent_bits;
}

// The first position at or after pos that starts no later sibling of the
// leaf before it (at most 7 steps), or n.
Status family_boundary(BTree& table, uint64_t n, uint64_t* pos) {
  if (*pos == 0 || *pos >= n) return Status::Ok();
  uint64_t before = 0, key = 0;
  WEAVER_RETURN_IF_ERROR(table.select(*pos - 1, &before, nullptr));
  while (*pos < n) {
    WEAVER_RETURN_IF_ERROR(table.select(*pos, &key, nullptr));
    if (!octant_keys_are_siblings(before, key)) break;
    before = key;
    ++*pos;
  }
  return Status::Ok();
}

}  // namespace

Status cut_equal_runs(BTree& table, int ranks, std::vector<uint64_t>* first_leaf,
                      std::vector<uint64_t>* start) {
  const uint64_t n = table.size();
  first_leaf->assign(ranks + 1, UINT64_MAX);
  start->assign(ranks + 1, UINT64_MAX);
  for (int r = 0; r < ranks; ++r) {
    uint64_t pos = n * uint64_t(r) / uint64_t(ranks);
    WEAVER_RETURN_IF_ERROR(family_boundary(table, n, &pos));
    if (pos >= n) break;
    WEAVER_RETURN_IF_ERROR(table.select(pos, &(*first_leaf)[r], nullptr));
    (*start)[r] = r == 0 ? 0 : octant_key_morton((*first_leaf)[r]);
  }
  return Status::Ok();
}

std::string units_to_metadata(const Units& u) {
  char buf[256];
  std::snprintf(buf, sizeof buf, "tick_m=%.17g;origin_m=%.17g,%.17g,%.17g", u.tick_m, u.origin_m[0],
                u.origin_m[1], u.origin_m[2]);
  return u.geo.empty() ? std::string(buf) : buf + (";geo=" + u.geo);
}

void for_each_metadata_item(const std::string& metadata,
                            const std::function<void(const std::string&, const std::string&)>& fn) {
  std::istringstream in(metadata);
  std::string item;
  while (std::getline(in, item, ';')) {
    const size_t eq = item.find('=');
    if (eq != std::string::npos) fn(item.substr(0, eq), item.substr(eq + 1));
  }
}

void units_from_metadata(const std::string& metadata, Units* u) {
  for_each_metadata_item(metadata, [u](const std::string& key, const std::string& value) {
    if (key == "tick_m") {
      std::sscanf(value.c_str(), "%lf", &u->tick_m);
    } else if (key == "origin_m") {
      std::sscanf(value.c_str(), "%lf,%lf,%lf", &u->origin_m[0], &u->origin_m[1], &u->origin_m[2]);
    } else if (key == "geo") {
      u->geo = value;
    }
  });
}

std::string levels_to_metadata(const LevelCounts& levels) {
  std::string out = ";levels=";
  for (size_t l = 0; l < levels.size(); ++l) {
    if (l > 0) out += ',';
    out += std::to_string(levels[l]);
  }
  return out;
}

bool levels_from_metadata(const std::string& metadata, LevelCounts* levels) {
  const size_t at = metadata.find("levels=");
  if (at == std::string::npos) return false;
  std::istringstream in(metadata.substr(at + 7));
  for (size_t l = 0; l < levels->size(); ++l) {
    std::string item;
    if (!std::getline(in, item, l + 1 < levels->size() ? ',' : ';')) return false;
    try {
      (*levels)[l] = std::stoull(item);
    } catch (...) {
      return false;
    }
  }
  return true;
}

std::string merge_shard_metadata(const std::vector<std::string>& shards) {
  if (shards.empty()) return "";
  LevelCounts sum{};
  for (const std::string& m : shards) {
    LevelCounts l{};
    if (!levels_from_metadata(m, &l)) return shards.front();  // nothing to sum
    for (size_t i = 0; i < sum.size(); ++i) sum[i] += l[i];
  }
  return with_levels(shards.front(), sum);  // the first shard's, with the sums
}

std::string with_levels(const std::string& metadata, const LevelCounts& levels) {
  const size_t at = metadata.find(";levels=");
  if (at == std::string::npos) return metadata + levels_to_metadata(levels);
  const size_t end = metadata.find(';', at + 1);
  return metadata.substr(0, at) + levels_to_metadata(levels) +
         (end == std::string::npos ? "" : metadata.substr(end));
}

int finest_level(const LevelCounts& levels) {
  for (int l = static_cast<int>(levels.size()) - 1; l > 0; --l) {
    if (levels[l] > 0) return l;
  }
  return 0;
}

}  // namespace weaver
