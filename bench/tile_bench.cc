// The tiles of `weaver serve` on a large mesh: the time to render one
// 256 x 256 tile of the section z = 1 km, coloured by vs, at zoom 0 (the
// whole plane in one tile), 3, 6 and 9 (random tiles that hold elements),
// against `weaver slice` of the whole plane (the picture a user had before).
// A tile reads only its pixels, so its time should not grow with the mesh.
// Default: the basin's 0.5 Hz mesh (built here); --db DB for any mesh (the
// 2 Hz one, say).  --cold also times tiles read from disk: before each, the
// database's files are dropped from the page cache (posix_fadvise) and the
// Explorer opened afresh, as a server started on a database not read since
// boot.  Prints one JSON object per measurement, then a table.
#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "basin_stages.h"
#include "bench_util.h"
#include "serve/tiles.h"

namespace weaver::bench {

// Drops db's files from the page cache: what the next read takes comes
// from the disk.
void evict(const std::string& db) {
  for (const auto& f : std::filesystem::directory_iterator(db)) {
    const int fd = ::open(f.path().c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) continue;
    (void)::posix_fadvise(fd, 0, 0, POSIX_FADV_DONTNEED);
    ::close(fd);
  }
}

double percentile95(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[std::min(v.size() - 1, size_t(0.95 * double(v.size())))];
}

int tile_main(int argc, char** argv) {
  std::string db;
  double freq = 0.5;
  int repeat = 5;
  bool cold = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--db" && i + 1 < argc) {
      db = argv[++i];
    } else if (a == "--freq" && i + 1 < argc) {
      freq = std::stod(argv[++i]);
    } else if (a == "--repeat" && i + 1 < argc) {
      repeat = std::stoi(argv[++i]);
    } else if (a == "--cold") {
      cold = true;
    } else {
      std::printf("usage: tile_bench [--db DB | --freq F] [--repeat N] [--cold]\n");
      return 2;
    }
  }
  const uint64_t memory = 256ull << 20;
  if (db.empty() && (db = basin_mesh(freq)).empty()) {
    return std::fprintf(stderr, "cannot build the %g Hz basin mesh\n", freq), 1;
  }

  std::unique_ptr<Explorer> ex;
  serve::Section s;
  serve::FieldRange range;
  double t0 = now_seconds();
  Status st = Explorer::open(db, MemoryBudget(memory), &ex);
  if (st.ok()) st = serve::section_of(*ex, 2, 1000, &s);
  const double section_s = now_seconds() - t0;
  // What each of weaver serve's threads does before its first request.
  t0 = now_seconds();
  if (st.ok()) st = ex->mesh().octants().prepare_lookups();
  if (st.ok() && ex->mesh().has_aggregates()) st = ex->mesh().aggregates().prepare_lookups();
  const double warm_s = now_seconds() - t0;
  // The least vs under each pixel (from the aggregate table, when the mesh
  // has one), and the vs at each pixel's centre.
  serve::Paint least, centre;
  if (st.ok()) st = serve::paint_of(*ex, "vs", "", &least);
  if (st.ok()) st = serve::paint_of(*ex, "vs", "centre", &centre);
  t0 = now_seconds();
  if (st.ok()) st = serve::field_range(*ex, s, least, &range);
  const double range_s = now_seconds() - t0;
  if (!st.ok()) return std::fprintf(stderr, "%s\n", st.message().c_str()), 1;
  std::vector<std::map<std::string, std::string>> table;
  auto emit = [&](const std::string& what, int zoom, std::vector<double> secs, uint64_t bytes) {
    Json j;
    j.add("bench", "tile").add("db", db).add("elements", ex->element_count()).add("what", what);
    if (zoom >= 0) j.add("zoom", zoom);
    j.add("median_s", median(secs)).add("p95_s", percentile95(secs));
    j.add("repeat", int(secs.size())).add("png_bytes", bytes);
    std::printf("%s\n", j.str().c_str());
    table.push_back({{"what", what},
                     {"zoom", zoom >= 0 ? std::to_string(zoom) : ""},
                     {"median ms", fmt(median(secs) * 1e3)},
                     {"p95 ms", fmt(percentile95(secs) * 1e3)},
                     {"png bytes", std::to_string(bytes)}});
  };
  emit("section (domain extent)", -1, {section_s}, 0);
  emit("warm-up (leaf directories)", -1, {warm_s}, 0);
  emit("colour range (256x256)", -1, {range_s}, 0);
  for (const serve::Paint& paint : {least, centre}) {
    std::mt19937_64 rng(7);  // the same tiles for both paints
    for (const int zoom : {0, 3, 6, 9}) {
      std::vector<double> secs;
      uint64_t bytes = 0;
      for (int r = 0; r < repeat; ++r) {
        // A tile inside the domain's square on the plane.
        const int64_t n = int64_t{1} << zoom;
        const double fx = s.extent[s.u] / s.side, fy = s.extent[s.v] / s.side;
        const int64_t x = int64_t(rng() % uint64_t(std::max<int64_t>(1, int64_t(n * fx))));
        const int64_t y = n - 1 - int64_t(rng() % uint64_t(std::max<int64_t>(1, int64_t(n * fy))));
        std::string png;
        t0 = now_seconds();
        st = serve::render_tile(*ex, s, paint, range.min, range.max, zoom, x, y, &png);
        secs.push_back(now_seconds() - t0);
        if (!st.ok()) return std::fprintf(stderr, "%s\n", st.message().c_str()), 1;
        bytes = png.size();
      }
      emit(std::string("tile, ") + serve::summary_name(paint.summary), zoom, secs, bytes);
    }
  }
  // Tiles read from disk: the files dropped from the page cache, a fresh
  // Explorer warmed as a server's thread is (its directories), the files
  // dropped again, then the tile; and the section's colour range the same way.
  for (const serve::Paint* paint : {&least, &centre}) {
    if (!cold) break;
    std::mt19937_64 rng(11);
    for (const int zoom : {-1, 0, 3, 6, 9}) {
      if (zoom < 0 && paint != &least) continue;  // the range is the least paint's
      std::vector<double> secs;
      for (int r = 0; r < repeat; ++r) {
        std::unique_ptr<Explorer> fresh;
        evict(db);
        st = Explorer::open(db, MemoryBudget(memory), &fresh);
        if (st.ok()) st = fresh->mesh().octants().prepare_lookups();
        if (st.ok() && fresh->mesh().has_aggregates()) {
          st = fresh->mesh().aggregates().prepare_lookups();
        }
        evict(db);
        const int64_t n = int64_t{1} << std::max(zoom, 0);
        const double fx = s.extent[s.u] / s.side, fy = s.extent[s.v] / s.side;
        const int64_t x = int64_t(rng() % uint64_t(std::max<int64_t>(1, int64_t(n * fx))));
        const int64_t y = n - 1 - int64_t(rng() % uint64_t(std::max<int64_t>(1, int64_t(n * fy))));
        std::string png;
        serve::FieldRange fresh_range;
        t0 = now_seconds();
        if (st.ok() && zoom < 0) st = serve::field_range(*fresh, s, least, &fresh_range);
        if (st.ok() && zoom >= 0) {
          st = serve::render_tile(*fresh, s, *paint, range.min, range.max, zoom, x, y, &png);
        }
        secs.push_back(now_seconds() - t0);
        if (!st.ok()) return std::fprintf(stderr, "%s\n", st.message().c_str()), 1;
      }
      emit(zoom < 0 ? std::string("colour range, from disk")
                    : std::string("tile from disk, ") + serve::summary_name(paint->summary),
           zoom, secs, 0);
    }
  }
  // How the least-vs pixels were made, zooms 0 to 6 (10 tiles each, not
  // timed): from the aggregate table or the leaves inside the pixel's
  // octant, or, past a tile's budget of leaves, from a wider octant.
  std::vector<std::map<std::string, std::string>> coverage;
  for (int zoom = 0; zoom <= 6; ++zoom) {
    std::mt19937_64 rng(zoom + 101);
    uint64_t pixels = 0, summarised = 0, wide = 0;
    for (int r = 0; r < 10; ++r) {
      const int64_t n = int64_t{1} << zoom;
      const int64_t x = int64_t(rng() % uint64_t(n)), y = int64_t(rng() % uint64_t(n));
      std::vector<serve::TilePixel> px;
      st = serve::tile_pixels(*ex, s, least, zoom, x, y, &px);
      if (!st.ok()) return std::fprintf(stderr, "%s\n", st.message().c_str()), 1;
      for (const serve::TilePixel& p : px) {
        pixels += p.inside;
        summarised += p.inside && p.lo != p.hi;
        wide += p.wide;
      }
    }
    Json j;
    j.add("bench", "tile").add("db", db).add("what", "least-vs pixels").add("zoom", zoom);
    j.add("pixels", pixels).add("summarised", summarised).add("from_wider_octant", wide);
    std::printf("%s\n", j.str().c_str());
    coverage.push_back({{"zoom", std::to_string(zoom)},
                        {"pixels inside", std::to_string(pixels)},
                        {"summarised", std::to_string(summarised)},
                        {"from a wider octant", std::to_string(wide)}});
  }
  std::vector<double> slice;
  for (int r = 0; r < std::min(repeat, 3); ++r) {
    uint64_t peak = 0;
    t0 = now_seconds();
    run_program({WEAVER_BINARY, "slice", db, "--axis", "z", "--at", "1000", "--units", "m",
                 "--color", "vs", "--out", "/tmp/weaver-tile-bench-slice.png"},
                &peak);
    slice.push_back(now_seconds() - t0);
  }
  emit("weaver slice, whole plane", -1, slice, 0);
  std::printf("\n%s: %llu elements\n", db.c_str(), (unsigned long long)ex->element_count());
  print_table(table, {"what", "zoom", "median ms", "p95 ms", "png bytes"});
  std::printf("\nleast-vs pixels of 10 random tiles a zoom:\n");
  print_table(coverage, {"zoom", "pixels inside", "summarised", "from a wider octant"});
  return 0;
}

}  // namespace weaver::bench

int main(int argc, char** argv) { return weaver::bench::tile_main(argc, argv); }
