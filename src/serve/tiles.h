// The map tiles of `weaver serve`: a cross-section of the mesh on an
// axis-aligned plane as 256 x 256 PNG tiles, in the tiling of web maps.
// Zoom 0 is one tile holding the whole section (a square as wide as the
// domain's larger extent along the plane), zoom z is 2^z x 2^z tiles, x to
// the right and y down as the page shows them: north up in a map view
// (a z plane), depth down in a section (x or y plane).
//
// A tile never reads more than its pixels: each pixel shows the element at
// its centre, found by one sorted batch of point lookups (Explorer's
// locate_batch, one forward walk), so a tile costs the same on a thousand
// elements or on a billion.  Where an element is many pixels wide its
// outline is drawn.
#pragma once

#include <cstdint>
#include <string>

#include "query/explorer.h"
#include "schema/status.h"

namespace weaver::serve {

// The section: its plane and the part of it the tiles cover, in ticks.
struct Section {
  int axis = 2;           // the plane's normal
  uint32_t at = 0;        // the plane, in ticks along axis
  int u = 0, v = 1;       // the in-plane axes: u across, v down or up the page
  bool down = false;      // v grows down the page (depth in sections)
  double extent[3] = {};  // the domain's extents, ticks
  double side = 0;        // the square zoom 0 shows
};

// How far the domain reaches from the origin corner along each axis, ticks
// (the whole root for a domain without its origin corner).
Status domain_extent(Explorer& ex, double extent[3]);

// The section through `at_m` metres along axis (InvalidArgument when the
// plane misses the domain or the axis is not 0..2).
Status section_of(Explorer& ex, int axis, double at_m, Section* s);
// The same with the domain's extents already known (domain_extent's).
Status section_of(Explorer& ex, const double extent[3], int axis, double at_m, Section* s);

// The colour fields: level, edge, vp, vs, rho, qp, qs.  InvalidArgument
// naming them for another name, or for a field the mesh lacks.
Status check_field(Explorer& ex, const std::string& field);

struct FieldRange {
  double min = 0, max = 0;
  uint64_t samples = 0;  // points of the section that hit an element
};
// The range of a field over the section, sampled on a 256 x 256 grid: the
// colour scale every tile of the section shares.
Status field_range(Explorer& ex, const Section& s, const std::string& field, FieldRange* r);

// Tile (zoom, x, y) of the section as PNG bytes, coloured by field over
// [lo, hi] on the viridis scale; outside the domain is transparent white.
Status render_tile(Explorer& ex, const Section& s, const std::string& field, double lo, double hi,
                   int zoom, int64_t x, int64_t y, std::string* png);

}  // namespace weaver::serve
