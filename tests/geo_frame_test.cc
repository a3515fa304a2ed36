// weaver's transverse Mercator against PROJ's cs2cs (Debian proj-bin) at
// thousands of points over a 200 km domain, both ways, within 1 mm; and the
// frame's rotation, round trip and text form.  Skipped where cs2cs is not
// installed, except under .ci/run (WEAVER_REQUIRE_TOOLS), which installs it.
#include "model/geo_frame.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <random>
#include <vector>

namespace weaver {
namespace {

bool have_cs2cs() { return std::system("command -v cs2cs >/dev/null 2>&1") == 0; }

// cs2cs's answer for each input line, as pairs.
std::vector<std::pair<double, double>> cs2cs(const std::string& args,
                                             const std::vector<std::pair<double, double>>& in) {
  const std::string dir = ::testing::TempDir();
  {
    std::ofstream f(dir + "geo_in.txt");
    f.precision(17);
    for (const auto& [a, b] : in) f << a << " " << b << "\n";
  }
  const std::string cmd =
      "cs2cs -f %.9f " + args + " < " + dir + "geo_in.txt > " + dir + "geo_out.txt";
  EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
  std::vector<std::pair<double, double>> out;
  std::ifstream f(dir + "geo_out.txt");
  double a, b, c;
  while (f >> a >> b >> c) out.emplace_back(a, b);
  return out;
}

struct Case {
  const char* name;
  TransverseMercator tm;
  std::string proj;  // the same projection for cs2cs
};

TEST(GeoFrame, TransverseMercatorAgreesWithCs2csWithinAMillimetre) {
  if (!have_cs2cs()) {
    if (std::getenv("WEAVER_REQUIRE_TOOLS")) FAIL() << "cs2cs (proj-bin) is required";
    GTEST_SKIP() << "cs2cs (proj-bin) is not installed";
  }
  const std::string wgs = "+proj=longlat +datum=WGS84 +to ";
  std::vector<Case> cases;
  // The paper's LA basin box origin; UTM 11 (Los Angeles) and 10 (the Bay
  // Area); a southern UTM zone; a high latitude.
  cases.push_back({"tmerc LA",
                   {-118.7, 33.58, 1, 0, 0},
                   "+proj=tmerc +lat_0=33.58 +lon_0=-118.7 +k=1 +x_0=0 +y_0=0 +ellps=WGS84"});
  cases.push_back({"utm 11", {-117, 0, 0.9996, 500000, 0}, "+proj=utm +zone=11 +datum=WGS84"});
  cases.push_back({"utm 10", {-123, 0, 0.9996, 500000, 0}, "+proj=utm +zone=10 +datum=WGS84"});
  cases.push_back({"utm 19 south",
                   {-69, 0, 0.9996, 500000, 10000000},
                   "+proj=utm +zone=19 +south +datum=WGS84"});
  cases.push_back({"tmerc 64N",
                   {25.5, 64, 1, 0, 0},
                   "+proj=tmerc +lat_0=64 +lon_0=25.5 +k=1 +x_0=0 +y_0=0 +ellps=WGS84"});
  const double centre[][2] = {
      {-118.2, 34.0}, {-117.9, 34.1}, {-122.3, 37.8}, {-70.6, -33.4}, {25.5, 64.5}};
  for (size_t k = 0; k < cases.size(); ++k) {
    const Case& c = cases[k];
    std::mt19937_64 rng(k + 1);
    std::vector<std::pair<double, double>> geo;
    for (int i = 0; i < 2000; ++i) {
      // Within about 100 km of the centre (a 200 km domain).
      const double lat = centre[k][1] + std::uniform_real_distribution<>(-0.9, 0.9)(rng);
      const double dlon = 0.9 / std::cos(lat * 3.14159265358979 / 180);
      geo.emplace_back(centre[k][0] + std::uniform_real_distribution<>(-dlon, dlon)(rng), lat);
    }
    const auto projected = cs2cs(wgs + c.proj, geo);
    ASSERT_EQ(projected.size(), geo.size()) << c.name;
    double worst = 0, worst_back = 0;
    for (size_t i = 0; i < geo.size(); ++i) {
      double e, n, lon, lat;
      c.tm.forward(geo[i].first, geo[i].second, &e, &n);
      worst =
          std::max({worst, std::abs(e - projected[i].first), std::abs(n - projected[i].second)});
      // Back from cs2cs's metres to degrees, measured in metres on the ground.
      c.tm.inverse(projected[i].first, projected[i].second, &lon, &lat);
      const double m_lat = (lat - geo[i].second) * 111320;
      const double m_lon = (lon - geo[i].first) * 111320 * std::cos(lat * 3.14159265358979 / 180);
      worst_back = std::max({worst_back, std::abs(m_lat), std::abs(m_lon)});
    }
    EXPECT_LT(worst, 1e-3) << c.name;
    EXPECT_LT(worst_back, 1e-3) << c.name;
  }
}

TEST(GeoFrame, AzimuthTurnsTheAxesAndTheFrameRoundTrips) {
  GeoFrame north;  // x north, y east (the default)
  ASSERT_TRUE(GeoFrame::parse("-118.7,33.58", &north).ok());
  EXPECT_EQ(north.azimuth, 0);
  GeoFrame east = north;  // x east, y south
  east.azimuth = 90;
  double x, y;
  north.to_frame(-118.7, 33.68, &x, &y);  // 0.1 degree north of the origin
  EXPECT_NEAR(x, 11092, 5);
  EXPECT_NEAR(y, 0, 1e-6);
  north.to_frame(-118.6, 33.58, &x, &y);  // east of the origin
  EXPECT_GT(y, 9000);
  EXPECT_NEAR(x, 0, 100);  // the parallel curves away from the grid's east
  east.to_frame(-118.7, 33.68, &x, &y);
  EXPECT_NEAR(x, 0, 1e-6);
  EXPECT_NEAR(y, -11092, 5);  // north is -y when x is east
  GeoFrame turned = east;
  turned.azimuth = 127.5;
  GeoFrame utm;
  ASSERT_TRUE(GeoFrame::parse("-118.7,33.58,40,utm11", &utm).ok());
  EXPECT_EQ(utm.utm_zone, 11);
  for (const GeoFrame* g : {&east, &north, &turned, &utm}) {
    double x0, y0;
    g->to_frame(g->lon0, g->lat0, &x0, &y0);
    EXPECT_NEAR(x0, 0, 1e-6);
    EXPECT_NEAR(y0, 0, 1e-6);
    for (double px : {-100000.0, 0.0, 37000.0, 100000.0}) {
      for (double py : {-100000.0, 5.0, 100000.0}) {
        double lon, lat, bx, by;
        g->to_geo(px, py, &lon, &lat);
        g->to_frame(lon, lat, &bx, &by);
        EXPECT_NEAR(bx, px, 1e-6);
        EXPECT_NEAR(by, py, 1e-6);
      }
    }
  }
  // Turning the frame keeps distances from the origin.
  double ex, ey, tx, ty;
  east.to_frame(-118.3, 33.9, &ex, &ey);
  turned.to_frame(-118.3, 33.9, &tx, &ty);
  EXPECT_NEAR(std::hypot(ex, ey), std::hypot(tx, ty), 1e-6);
  EXPECT_EQ(utm.to_text(), "-118.7,33.58,40,utm11");
  GeoFrame back;
  ASSERT_TRUE(GeoFrame::parse(turned.to_text(), &back).ok());
  EXPECT_EQ(back.azimuth, 127.5);
  for (const char* bad : {"", "1", "a,b", "1,2,3,4", "200,0", "0,89", "1,2,utm61", "1,2,utmx"}) {
    EXPECT_FALSE(GeoFrame::parse(bad, &back).ok()) << bad;
  }
}

}  // namespace
}  // namespace weaver
