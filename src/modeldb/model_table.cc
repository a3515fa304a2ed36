#include "modeldb/model_table.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <vector>

#include "db/octant_table.h"

namespace weaver {

namespace {

// Metadata values may not hold the separators.
std::string clean(std::string s) {
  for (char& c : s) {
    if (c == ';' || c == '\n' || c == '\r') c = ',';
  }
  return s;
}

}  // namespace

std::string model_info_to_metadata(const ModelInfo& m) {
  Units u;
  u.tick_m = m.tick_m;
  u.origin_m = m.origin_m;
  char buf[200];
  std::snprintf(buf, sizeof buf, ";extent_m=%.17g,%.17g,%.17g;q=%d", m.extent_m[0], m.extent_m[1],
                m.extent_m[2], m.has_q ? 1 : 0);
  return units_to_metadata(u) + buf + ";source=" + clean(m.source) + ";geo=" + clean(m.geo) +
         ";producer=" + clean(m.producer);
}

void model_info_from_metadata(const std::string& metadata, ModelInfo* m) {
  Units u;
  units_from_metadata(metadata, &u);
  m->tick_m = u.tick_m;
  m->origin_m = u.origin_m;
  for_each_metadata_item(metadata, [m](const std::string& key, const std::string& value) {
    if (key == "extent_m") {
      std::sscanf(value.c_str(), "%lf,%lf,%lf", &m->extent_m[0], &m->extent_m[1], &m->extent_m[2]);
    } else if (key == "q") {
      m->has_q = value == "1";
    } else if (key == "source") {
      m->source = value;
    } else if (key == "geo") {
      m->geo = value;
    } else if (key == "producer") {
      m->producer = value;
    }
  });
}

namespace {

bool labase_form(const std::string& t, double* root, ModelInfo* m) {
  double lat, lon, dep, x, y, z;
  if (std::sscanf(t.c_str(),
                  "LABASE latfrom %lf lonfrom %lf depfrom %lf xsize %lf ysize %lf zsize %lf", &lat,
                  &lon, &dep, &x, &y, &z) != 6)
    return false;
  *root = std::max({x, y, z});  // createcvm's domain_rootsize
  m->extent_m = {x, y, z};
  char buf[100];
  std::snprintf(buf, sizeof buf, "%.9g,%.9g,0", lon, lat);
  m->geo = buf;
  return true;
}

bool cmu_form(const std::string& t, double* root, ModelInfo* m) {
  char title[256], author[256], date[256], schema[256];
  unsigned fields, ticks[3];
  double lat, lon, dims[3], depth;
  if (std::sscanf(t.c_str(),
                  "Title:%255s Author:%255s Date:%255s %u %255s %lf %lf %lf %lf %lf %lf %u %u %u",
                  title, author, date, &fields, schema, &lat, &lon, &dims[0], &dims[1], &depth,
                  &dims[2], &ticks[0], &ticks[1], &ticks[2]) != 14)
    return false;
  if (ticks[0] == 0) return false;
  *root = dims[0] / ticks[0] * 2147483648.0;
  m->extent_m = {dims[0], dims[1], dims[2]};
  char buf[100];
  std::snprintf(buf, sizeof buf, "%.9g,%.9g,0", lon, lat);
  m->geo = buf;
  return true;
}

bool ucvm_form(const std::string& t, double* root, ModelInfo* m) {
  std::vector<std::string> parts;
  std::istringstream in(t);
  for (std::string p; std::getline(in, p, '|');) parts.push_back(p);
  if (parts.size() != 13 || parts[0] != "SCEC_CVM_V1") return false;
  double lon, lat, depth, rot, dims[3];
  unsigned ticks[3];
  if (std::sscanf(parts[9].c_str(), "%lf,%lf,%lf", &lon, &lat, &depth) != 3 ||
      std::sscanf(parts[10].c_str(), "%lf", &rot) != 1 ||
      std::sscanf(parts[11].c_str(), "%lf,%lf,%lf", &dims[0], &dims[1], &dims[2]) != 3 ||
      std::sscanf(parts[12].c_str(), "%u,%u,%u", &ticks[0], &ticks[1], &ticks[2]) != 3 ||
      ticks[0] == 0)
    return false;
  *root = dims[0] / ticks[0] * 2147483648.0;
  m->extent_m = {dims[0], dims[1], dims[2]};
  char buf[160];
  std::snprintf(buf, sizeof buf, "%.9g,%.9g,%.9g", lon, lat, rot);
  m->geo = buf;
  // A UTM projection string ("+proj=utm +zone=10 [+south]") names the zone.
  const size_t zone = parts[8].find("+zone=");
  if (parts[8].find("+proj=utm") != std::string::npos && zone != std::string::npos) {
    m->geo += ",utm" + std::to_string(std::atoi(parts[8].c_str() + zone + 6)) +
              (parts[8].find("+south") != std::string::npos ? "s" : "");
  }
  m->producer = "projection " + parts[8];
  return true;
}

}  // namespace

Status etree_placement(const std::string& text, double* root_edge_m, ModelInfo* info) {
  if (labase_form(text, root_edge_m, info) || cmu_form(text, root_edge_m, info) ||
      ucvm_form(text, root_edge_m, info)) {
    if (!(*root_edge_m > 0) || !std::isfinite(*root_edge_m)) {
      return Status::Corruption("the etree metadata gives a size that is not positive");
    }
    return Status::Ok();
  }
  return Status::NotFound("cannot tell the etree's size in metres from its metadata ('" +
                          text.substr(0, 80) + "'): give --root-edge METRES");
}

}  // namespace weaver
