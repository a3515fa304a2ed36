// Where a model's or mesh's frame lies on the Earth: its origin (x = y = 0)
// as WGS84 longitude and latitude, the azimuth of its x axis (degrees
// clockwise from north; 0, the default, puts x north), and the projection
// between the two: a transverse Mercator about the origin (scale 1 on the
// origin's meridian), or a UTM zone (--utm-zone) with the frame's origin at
// the origin's UTM coordinates.  y points 90 degrees clockwise from x and z
// down, a right-handed frame: north, east, down by default, the frame of
// Hercules and the CMU CVM etrees (whose metadata gives azimuth 0).
//
//   x = dE sin(az) + dN cos(az)        dE, dN: projected metres from the
//   y = dE cos(az) - dN sin(az)        origin's projected position
//
// The projection is Krüger's series to sixth order in the third flattening
// (Karney, "Transverse Mercator with an accuracy of a few nanometers", J.
// Geodesy 85, 2011, eqs. 35-36 and the coefficients of his section 4):
// well under a millimetre within thousands of kilometres of the meridian.
// tests/geo_frame_test.cc checks it against PROJ's cs2cs.
//
// Text form (metadata, --origin-geo): "LON,LAT[,AZ][,utmZONE[s]]", e.g.
// "-118.7,33.58,0" or "-118.7,33.58,0,utm11".
#pragma once

#include <string>

#include "schema/status.h"

namespace weaver {

struct GeoFrame {
  double lon0 = 0, lat0 = 0;  // degrees, WGS84
  double azimuth = 0;         // of x, degrees clockwise from north
  int utm_zone = 0;           // 0: transverse Mercator about the origin
  bool utm_south = false;

  // Metres in the frame from longitude, latitude (degrees), and back.  For
  // many points, GeoTransform does the same without redoing the setup.
  void to_frame(double lon, double lat, double* x, double* y) const;
  void to_geo(double x, double y, double* lon, double* lat) const;

  std::string to_text() const;
  // Parses the text form; InvalidArgument naming what is wrong.
  static Status parse(const std::string& text, GeoFrame* out);
};

// The projection alone: transverse Mercator on WGS84 about central meridian
// lon_c (degrees), scale k0, false easting and northing, latitude of origin
// lat_o.  Exposed for the test against cs2cs.
struct TransverseMercator {
  double lon_c = 0, lat_o = 0, k0 = 1, false_e = 0, false_n = 0;
  void forward(double lon, double lat, double* e, double* n) const;
  void inverse(double e, double n, double* lon, double* lat) const;
};

// A GeoFrame's maps with their constants worked out once (the origin's
// projected position, the azimuth's sine and cosine): for every node of an
// export, every point of a batch.
class GeoTransform {
 public:
  explicit GeoTransform(const GeoFrame& g);
  void to_frame(double lon, double lat, double* x, double* y) const;
  void to_geo(double x, double y, double* lon, double* lat) const;

 private:
  TransverseMercator tm_;
  double xi0_, sin_, cos_, e0_ = 0, n0_ = 0;
};

}  // namespace weaver
