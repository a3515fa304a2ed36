// A georeferenced mesh end to end: construct --origin-geo --azimuth, the raw
// export's node_lonlat (against cs2cs where it is installed), the vtu's
// longitude and latitude arrays, and query --geo answering as the frame's
// metres do.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "bench_util.h"
#include "model/geo_frame.h"
#include "test_util.h"

namespace weaver {
namespace {

using testing::slurp;

// The byte offset of a raw export's array, from mesh.json.
uint64_t offset_of(const std::string& json, const std::string& array) {
  const size_t at = json.find("\"" + array + "\"");
  EXPECT_NE(at, std::string::npos) << array;
  const size_t off = json.find("\"offset\": ", at);
  return std::stoull(json.substr(off + 10));
}

std::string run(const std::vector<std::string>& args) {
  uint64_t rss = 0;
  std::vector<std::string> all = {WEAVER_BINARY};
  all.insert(all.end(), args.begin(), args.end());
  return bench::run_program(all, &rss);
}

TEST(GeoMesh, ExportsAndQueriesKnowWhereTheMeshIs) {
  const std::string dir = ::testing::TempDir() + "geo_mesh";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string db = dir + "/mesh.db";
  const std::string mesh =
      run({"mesh", db, "--model", "basin", "--freq", "0.05", "--domain", "40000,40000,20000",
           "--origin-geo", "-118.7,33.58", "--azimuth", "30", "--quiet"});
  ASSERT_NE(mesh.find("geo        origin lon,lat,azimuth -118.7,33.58,30"), std::string::npos)
      << mesh;
  GeoFrame frame;
  ASSERT_TRUE(GeoFrame::parse("-118.7,33.58,30", &frame).ok());

  run({"export", db, "--format", "raw", "--out", dir + "/raw", "--quiet"});
  const std::string json = slurp(dir + "/raw/mesh.json");
  ASSERT_NE(json.find("\"geo\": \"-118.7,33.58,30\""), std::string::npos) << json;
  const std::string bin = slurp(dir + "/raw/mesh.bin");
  const uint64_t nodes = std::stoull(json.substr(json.find("\"nodes\": ") + 9));
  const uint64_t coords = offset_of(json, "node_coords"), lonlat = offset_of(json, "node_lonlat");
  ASSERT_GT(nodes, 100u);
  ASSERT_GE(bin.size(), lonlat + 16 * nodes);
  std::vector<std::array<double, 4>> sample;  // x, y, lon, lat
  for (uint64_t i = 0; i < nodes; i += nodes / 97) {
    double xyz[3], ll[2];
    std::memcpy(xyz, bin.data() + coords + 24 * i, 24);
    std::memcpy(ll, bin.data() + lonlat + 16 * i, 16);
    double x, y;
    frame.to_frame(ll[0], ll[1], &x, &y);
    ASSERT_NEAR(x, xyz[0], 1e-5) << i;
    ASSERT_NEAR(y, xyz[1], 1e-5) << i;
    sample.push_back({xyz[0], xyz[1], ll[0], ll[1]});
  }

  // The same longitudes and latitudes through PROJ: its easting and
  // northing, turned by the azimuth, are the nodes' x and y.
  if (std::system("command -v cs2cs >/dev/null 2>&1") == 0) {
    {
      std::ofstream in(dir + "/lonlat.txt");
      in.precision(17);
      for (const auto& s : sample) in << s[2] << " " << s[3] << "\n";
    }
    const std::string cmd =
        "cs2cs -f %.6f +proj=longlat +datum=WGS84 +to +proj=tmerc +lat_0=33.58 +lon_0=-118.7 "
        "+k=1 +x_0=0 +y_0=0 +ellps=WGS84 < " +
        dir + "/lonlat.txt > " + dir + "/en.txt";
    ASSERT_EQ(std::system(cmd.c_str()), 0);
    std::ifstream en(dir + "/en.txt");
    const double az = 30 * 3.14159265358979323846 / 180;
    for (const auto& s : sample) {
      double e, n, h;
      ASSERT_TRUE(en >> e >> n >> h);
      EXPECT_NEAR(e * std::sin(az) + n * std::cos(az), s[0], 1e-3);
      EXPECT_NEAR(e * std::cos(az) - n * std::sin(az), s[1], 1e-3);
    }
  } else if (std::getenv("WEAVER_REQUIRE_TOOLS")) {
    FAIL() << "cs2cs (proj-bin) is required";
  }

  run({"export", db, "--format", "vtu", "--out", dir + "/mesh.vtu", "--quiet"});
  const std::string vtu = slurp(dir + "/mesh.vtu").substr(0, 4000);
  EXPECT_NE(vtu.find("Name=\"longitude\""), std::string::npos);
  EXPECT_NE(vtu.find("Name=\"latitude\""), std::string::npos);

  // query --geo: the answer the frame's metres give, one point and a batch.
  std::ofstream points(dir + "/points.txt");
  points.precision(17);
  for (size_t i = 0; i < sample.size(); i += 7) {
    // Inside the elements, not on their faces: 1234 m down.
    double lon, lat;
    frame.to_geo(sample[i][0] + 3.5, sample[i][1] + 2.5, &lon, &lat);
    const std::string by_geo = run({"query", db, "material", "--geo", std::to_string(lon),
                                    std::to_string(lat), "1234", "--format", "csv"});
    double x, y;
    frame.to_frame(std::stod(std::to_string(lon)), std::stod(std::to_string(lat)), &x, &y);
    char xs[64], ys[64];
    std::snprintf(xs, sizeof xs, "%.17g", x);
    std::snprintf(ys, sizeof ys, "%.17g", y);
    const std::string by_m =
        run({"query", db, "material", xs, ys, "1234", "--units", "m", "--format", "csv"});
    const auto values = [](const std::string& csv) {  // status onwards, without x y z
      const std::string row = csv.substr(csv.find('\n') + 1);
      size_t at = 0;
      for (int comma = 0; comma < 3; ++comma) at = row.find(',', at) + 1;
      return row.substr(at);
    };
    ASSERT_EQ(values(by_geo), values(by_m)) << by_geo << by_m;
    EXPECT_NE(by_geo.find("inside"), std::string::npos) << by_geo;
    points << lon << " " << lat << " 1234\n";
  }
  points.close();
  const std::string batch =
      run({"query", db, "material", "--geo", "--points", dir + "/points.txt", "--format", "csv"});
  EXPECT_EQ(std::count(batch.begin(), batch.end(), '\n'), 1 + (sample.size() + 6) / 7) << batch;
  EXPECT_EQ(batch.find(",bad,"), std::string::npos) << batch;

  // Without a place on the Earth, --geo is refused in one line.
  const std::string plain = dir + "/plain.db";
  run({"mesh", plain, "--model", "halfspace", "--freq", "0.02", "--quiet"});
  const std::string cmd = std::string(WEAVER_BINARY) + " query " + plain +
                          " material --geo -118 34 10 2>" + dir + "/err.txt";
  EXPECT_EQ(WEXITSTATUS(std::system(cmd.c_str())), 1);
  EXPECT_NE(slurp(dir + "/err.txt").find("not georeferenced"), std::string::npos);
}

}  // namespace
}  // namespace weaver
