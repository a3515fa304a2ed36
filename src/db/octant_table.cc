#include "db/octant_table.h"

#include <cstdio>
#include <sstream>

namespace weaver {

std::string units_to_metadata(const Units& u) {
  char buf[256];
  std::snprintf(buf, sizeof buf, "tick_m=%.17g;origin_m=%.17g,%.17g,%.17g", u.tick_m,
                u.origin_m[0], u.origin_m[1], u.origin_m[2]);
  return buf;
}

void units_from_metadata(const std::string& metadata, Units* u) {
  std::istringstream in(metadata);
  std::string item;
  while (std::getline(in, item, ';')) {
    const size_t eq = item.find('=');
    if (eq == std::string::npos) continue;
    const std::string key = item.substr(0, eq), value = item.substr(eq + 1);
    if (key == "tick_m") {
      std::sscanf(value.c_str(), "%lf", &u->tick_m);
    } else if (key == "origin_m") {
      std::sscanf(value.c_str(), "%lf,%lf,%lf", &u->origin_m[0], &u->origin_m[1], &u->origin_m[2]);
    }
  }
}

}  // namespace weaver
