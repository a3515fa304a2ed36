// The octant table: leaves of an octree keyed by packed octant key, and the
// physical units kept in its metadata.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "schema/octant.h"
#include "schema/status.h"

namespace weaver {

class BTree;

inline constexpr char kOctantTable[] = "octants";

// Whether the octant with key `holder` is o or an ancestor of o.
inline bool key_holds(uint64_t holder, const Octant& o) {
  const Octant h = octant_from_key(holder);
  return h == o || octant_is_ancestor(h, o);
}

// The leaf of an octant table that is `o` or holds it: the floor of o's
// key, when that leaf is o or an ancestor of o; *found false otherwise (o
// is cut into smaller leaves, or lies in a hole).  payload may be null.
Status floor_holding(BTree& table, const Octant& o, uint64_t* key, std::byte* payload, bool* found);

// The table cut into `ranks` runs of equal count, the parts of a parallel
// stage: rank r's leaves begin at position n*r/ranks, moved forward (by at
// most 7) so that no cut falls between two siblings: a family of leaves
// stays with one rank, so that it could be coarsened there (the rule of
// p4est_partition_for_coarsening in cburstedde/p4est, which moves a cut to
// the nearest boundary of a whole family; here forward).  first_leaf[r] is
// its first leaf's key, start[r] the Morton code its part of space begins at
// (0 for rank 0); UINT64_MAX for a rank without leaves at the end and for
// r = ranks (each gets ranks + 1 entries).  A rank whose run is empty before
// another's has first_leaf[r] == first_leaf[r + 1].
Status cut_equal_runs(BTree& table, int ranks, std::vector<uint64_t>* first_leaf,
                      std::vector<uint64_t>* start);
// The rank whose part of space holds Morton code m: the last r with
// start[r] <= m (ranks without leaves, whose start equals the next one's,
// are passed over).  start as cut_equal_runs gives it.
inline size_t rank_holding(const std::vector<uint64_t>& start, uint64_t m) {
  return std::upper_bound(start.begin(), start.end(), m) - start.begin() - 1;
}

// Physical placement of the tick grid: point (x, y, z) in ticks is at
// origin + tick * (x, y, z) metres.
struct Units {
  double tick_m = 1.0;
  std::array<double, 3> origin_m = {0, 0, 0};
  // Where the frame lies on the Earth, in model/geo_frame.h's text form
  // ("LON,LAT,AZIMUTH[,utmZONE]"); "" when the mesh is not georeferenced.
  std::string geo;
};

// Metadata text: "tick_m=<v>;origin_m=<x>,<y>,<z>[;geo=<text>]".
std::string units_to_metadata(const Units& u);
// Calls fn(key, value) for each "key=value" item of ";"-separated metadata
// text, in order; items without "=" are skipped.
void for_each_metadata_item(const std::string& metadata,
                            const std::function<void(const std::string&, const std::string&)>& fn);
// Fills *u from metadata; unknown or missing fields keep their defaults.
void units_from_metadata(const std::string& metadata, Units* u);

// The metadata of a sharded octant table (db/database.h) from its shards': the
// first shard's, with the items that count records ("levels=") summed over
// the shards, so that it reads as the metadata of one table of all their
// records would (and 'weaver compact' writes that table byte for byte).
std::string merge_shard_metadata(const std::vector<std::string>& shards);

// Leaves per level, kept in the metadata by the writer of the table
// (";levels=n0,n1,...,n20") so that readers need not scan for them.
using LevelCounts = std::array<uint64_t, 21>;
std::string levels_to_metadata(const LevelCounts& levels);
// False if the metadata has no (well-formed) level counts.
bool levels_from_metadata(const std::string& metadata, LevelCounts* levels);
// metadata with its ";levels=" item replaced by these counts, in its place
// (appended when it has none).
std::string with_levels(const std::string& metadata, const LevelCounts& levels);
// The finest level with leaves (0 if none).
int finest_level(const LevelCounts& levels);

}  // namespace weaver
