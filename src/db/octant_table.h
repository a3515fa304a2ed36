// The octant table: leaves of an octree keyed by packed octant key, and the
// physical units kept in its metadata.
#pragma once

#include <array>
#include <string>

namespace weaver {

inline constexpr char kOctantTable[] = "octants";

// Physical placement of the tick grid: point (x, y, z) in ticks is at
// origin + tick * (x, y, z) metres.
struct Units {
  double tick_m = 1.0;
  std::array<double, 3> origin_m = {0, 0, 0};
};

// Metadata text: "tick_m=<v>;origin_m=<x>,<y>,<z>".
std::string units_to_metadata(const Units& u);
// Fills *u from metadata; unknown or missing fields keep their defaults.
void units_from_metadata(const std::string& metadata, Units* u);

}  // namespace weaver
