// The map tiles of `weaver serve`: a cross-section of the mesh on an
// axis-aligned plane as 256 x 256 PNG tiles, in the tiling of web maps.
// Zoom 0 is one tile holding the whole section (a square as wide as the
// domain's larger extent along the plane), zoom z is 2^z x 2^z tiles, x to
// the right and y down as the page shows them: north up in a map view
// (a z plane), depth down in a section (x or y plane).
//
// A tile never reads more than its pixels, so it costs the same on a
// thousand elements or on a billion: one sorted batch of point lookups finds
// the element at each pixel's centre (Explorer's locate_batch, one forward
// walk).  Where that element is smaller than the pixel and the database has
// an aggregate table (query/aggregates.h), the pixel shows instead a summary
// of the elements in the octant of the pixel's size around its centre (the
// least vs, say).  Where the table holds the pixels' level, a batch of
// aggregate hits goes first, and only the pixels it has no record for look
// for their element; for pixels finer than the table's finest level the
// summaries are worked out from the leaves inside (about kOnTheFlyLeaves of
// them a tile; past that, from the table's finest octant around the pixel,
// wider than it).  Where an element is many pixels wide its outline is
// drawn.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

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

// What a pixel shows: a field (level, edge, vp, vs, rho, qp, qs) and, where
// the pixel holds many elements, which summary of them.
struct Paint {
  enum class Summary { kCentre, kMin, kMax, kMean };
  std::string field = "level";
  Summary summary = Summary::kCentre;  // kCentre: the element at the centre
};

// The paint of field with summary "min", "max", "mean" or "centre" ("":
// the field's own: the least vp, vs, qp, qs and edge, the mean rho, the
// finest level).  Without an aggregate table every summary is kCentre.
// InvalidArgument naming the choices for another name, for a field the mesh
// lacks, or for the mean of level or edge.
Status paint_of(Explorer& ex, const std::string& field, const std::string& summary, Paint* out);
// "min", "max", "mean" or "centre".
const char* summary_name(Paint::Summary s);
// The colour bar's words: "least vs of the elements in each pixel" or "vs
// of the element at each pixel's centre".
std::string paint_caption(const Paint& p);

struct FieldRange {
  double min = 0, max = 0;
  uint64_t samples = 0;  // points of the section that hit an element
};
// The range of the paint's field over the section, from the 256 x 256
// pixels of zoom 0 (their least and greatest values where summarised): the
// colour scale every tile of the section shares.
Status field_range(Explorer& ex, const Section& s, const Paint& paint, FieldRange* r);

inline constexpr int kTile = 256;  // pixels across and down
// A tile past the aggregate table's finest level begins no further octant
// once it has read this many leaves to summarise its pixels (some 10 ms).
inline constexpr uint64_t kOnTheFlyLeaves = 1 << 20;

// One pixel of a tile: the element at its centre, and the value the pixel
// shows with the least and greatest values under it (all three the
// element's unless summarised).
struct TilePixel {
  bool inside = false;  // false: outside the domain
  uint64_t id = 0;
  Octant leaf;  // the element at the centre
  double value = 0, lo = 0, hi = 0;
  // Summarised from an octant wider than the pixel: past the table's
  // finest level and past kOnTheFlyLeaves.
  bool wide = false;
};
// The kTile x kTile pixels of tile (zoom, x, y), row by row from the top of
// the page.
Status tile_pixels(Explorer& ex, const Section& s, const Paint& paint, int zoom, int64_t x,
                   int64_t y, std::vector<TilePixel>* out);

// Tile (zoom, x, y) of the section as PNG bytes, coloured by paint over
// [lo, hi] on the viridis scale; a pixel outside every element (beside the
// domain, or in the air over a ground) is transparent.  A vertical section
// of a mesh under a ground draws the ground line across it.
// With danglings, the dangling nodes that lie on the plane are marked as
// `weaver slice --danglings` marks them (edge-dangling red, face-dangling
// white), on elements at least 6 pixels wide: only a plane on element
// faces (z = 0, say) has nodes on it.
Status render_tile(Explorer& ex, const Section& s, const Paint& paint, double lo, double hi,
                   int zoom, int64_t x, int64_t y, std::string* png, bool danglings = false);

}  // namespace weaver::serve
