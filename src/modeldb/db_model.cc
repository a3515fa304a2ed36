#include "modeldb/db_model.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>

#include "db/database.h"
#include "schema/octant.h"
#include "storage/btree.h"

namespace weaver {

namespace {
std::atomic<uint64_t> g_next_serial{1};
}  // namespace

struct DbModel::Reader {
  std::unique_ptr<BTree> table;
  Status opened;
  ModelRegion region;
  // An octant the table gave: [lo, lo + edge) ticks on each axis.
  struct Found {
    Coord lo{0, 0, 0};
    uint32_t edge = 0;  // 0: none
    ModelValues values{};
    Octant octant;
    bool holds(Coord t) const {
      return t.x - lo.x < edge && t.y - lo.y < edge && t.z - lo.z < edge;
    }
  };
  Found last;
  // Octants the table gave, by a hash of the point's cell of 1024 ticks
  // (about a model cell at 100 m): points outside the region (the lattices
  // of the octants around a subtree, judged by its balance) come again and
  // again, shared by a parent's lattice and its children's and by
  // neighbours' faces, and a search of the table for each cost more than
  // the rest of their judgement.  About 220 KiB, made at the first search.
  static constexpr size_t kSeen = 4096;
  std::vector<Found> seen;
  Found& seen_slot(Coord t) {
    if (seen.empty()) seen.resize(kSeen);
    const uint64_t h = (uint64_t{t.x >> 10} * 0x9E3779B97F4A7C15ull) ^
                       (uint64_t{t.y >> 10} * 0xC2B2AE3D27D4EB4Full) ^
                       (uint64_t{t.z >> 10} * 0x165667B19E3779F9ull);
    return seen[(h >> 40) % kSeen];
  }
};

DbModel::~DbModel() = default;

Status DbModel::open(const std::string& dir, MemoryBudget memory, int threads,
                     std::unique_ptr<DbModel>* out) {
  std::unique_ptr<DbModel> m(new DbModel());
  m->dir_ = dir;
  m->serial_ = g_next_serial.fetch_add(1);
  WEAVER_RETURN_IF_ERROR(Database::open(dir, Database::Mode::kRead, false, &m->db_));
  if (!m->db_->has_table(kModelTable)) {
    return Status::NotFound(dir + ": no model table (make one with 'weaver model import')");
  }
  const uint64_t per_reader = memory.bytes() / std::max(1, threads);
  // Half the reader's share is its table's: a quarter its page cache, a
  // quarter its part of the leaves the regions' scans keep decoded, one
  // store for every reader (neighbouring regions read the same leaves: at
  // 1 Hz from the 100 m model database, the leaves one construct read,
  // replayed through 128 kept, found 75% there; on two threads, each
  // keeping its own, 2.3x the leaves were decoded).
  // Under 64 MB a reader, none are kept: its page cache, full there, keeps
  // the half (a peak RSS within --memory 64M).
  const bool keep = per_reader >= (64ull << 20);
  m->pool_bytes_ = std::max<uint64_t>(per_reader / (keep ? 4 : 2), 1ull << 20);
  if (keep) m->decoded_ = std::make_unique<DecodedLeaves>(per_reader / 4 * std::max(1, threads));
  // The raster: up to 1M cells where a quarter of the reader's share affords
  // them (construct from the 100 m model database: 0.82x the time of 256K
  // cells at 0.5 Hz on one thread, 0.98x at 1 Hz on two; coarser cells sent
  // more points to search a mixed cell's octants), never fewer than 32K.
  // (Never fewer than 256K, 3.7 MB, and the reader's half at --memory 32M
  // on two threads left room for 4096 octants, fewer than a subtree's
  // region holds: every point searched the table, and the 1 Hz construct
  // took 70 s, not 15.8 s.)
  m->region_cells_ = ModelRegion::kMinCells;
  while (m->region_cells_ < ModelRegion::kMaxCells &&
         2 * m->region_cells_ * ModelRegion::kBytesPerCell <= per_reader / 4) {
    m->region_cells_ *= 2;
  }
  // A region octant takes its key and values (the region makes room for
  // region_octants_ of them once, and never grows past); the octants seen
  // outside it about 220 KiB.  (Counted twice over, as vectors growing by
  // doubling would hold, the regions of a 0.5 Hz construct from the 100 m
  // model database on two threads at the default --memory did not fit:
  // every point of those subtrees then searched the table: 2.1x the time.)
  // All the half the raster and those leave is the region's: at --memory
  // 16M on two threads, 30K octants (when a megabyte had to be left over
  // first, 4096, and the 1 Hz construct took 71.5 s, not 21.9 s).
  const uint64_t fixed =
      m->region_cells_ * ModelRegion::kBytesPerCell + Reader::kSeen * sizeof(Reader::Found);
  const uint64_t region_bytes = per_reader / 2 > fixed ? per_reader / 2 - fixed : 0;
  m->region_octants_ = std::max<size_t>(region_bytes / (8 + sizeof(ModelValues)), 4096);
  std::unique_ptr<BTree> t;
  WEAVER_RETURN_IF_ERROR(m->db_->open_table(kModelTable, m->pool_bytes_, &t));
  model_info_from_metadata(t->options().metadata, &m->info_);
  m->octants_ = t->size();
  m->inv_tick_ = 1 / m->info_.tick_m;
  for (int a = 0; a < 3; ++a) {
    const double ticks = std::floor(m->info_.extent_m[a] / m->info_.tick_m + 1e-6);
    m->limit_[a] = static_cast<uint32_t>(std::clamp(ticks - 1, 0.0, double(kRootEdge - 1)));
    m->origin_[a] = m->info_.origin_m[a];
    m->inner_top_[a] = m->info_.extent_m[a] == 0 ? 0.0 : double(m->limit_[a]);
  }
  *out = std::move(m);
  return Status::Ok();
}

// The calling thread's reader: remembered in the thread (a lock and a map
// lookup for each octant construct visits cost as much as the answer).
DbModel::Reader& DbModel::reader() const {
  thread_local uint64_t cached_serial = 0;
  thread_local Reader* cached = nullptr;
  if (cached_serial == serial_) return *cached;
  std::lock_guard<std::mutex> lock(mu_);
  auto& r = readers_[std::this_thread::get_id()];
  if (!r) {
    r = std::make_unique<Reader>();
    r->region.set_max_cells(region_cells_);
    r->region.set_decoded_leaves(decoded_.get());
    r->opened = db_->open_table(kModelTable, pool_bytes_, &r->table);
  }
  cached_serial = serial_;
  cached = r.get();
  return *r;
}

// floor(d / tick), clamped into the box, by a multiplication and a cast,
// corrected by one where the product rounded across a whole number: the
// division and libm's floor (no SSE4.1 in the baseline) were a tenth of
// construct.
uint32_t DbModel::pixel_near_edge(int a, double m, bool* clamped) const {
  if (info_.extent_m[a] == 0) return 0;  // the model does not vary along this axis
  const double d = m - info_.origin_m[a];
  const double t = d * inv_tick_;
  if (!(t >= 0)) {  // before the box (or NaN)
    *clamped = true;
    return 0;
  }
  if (t >= double(limit_[a]) + 2) {
    *clamped = true;
    return limit_[a];
  }
  const int64_t k = floor_ticks(d, t);
  if (k < 0 || k > int64_t{limit_[a]}) {
    *clamped = true;
    return k < 0 ? 0 : limit_[a];
  }
  return static_cast<uint32_t>(k);
}

namespace {
const char kAxes[] = "xyz";
}  // namespace

Status DbModel::outside_box(double x, double y, double z) const {
  std::string box;
  for (int a = 0; a < 3; ++a) {
    if (info_.extent_m[a] == 0) continue;  // everywhere inside along this axis
    char buf[96];
    std::snprintf(buf, sizeof buf, "%s%c %g..%g", box.empty() ? "" : ", ", kAxes[a],
                  info_.origin_m[a], info_.origin_m[a] + info_.extent_m[a]);
    box += buf;
  }
  char buf[160];
  std::snprintf(buf, sizeof buf, "point (%g, %g, %g) m is outside the model's box (", x, y, z);
  return Status::NotFound(buf + box + " m)");
}

std::string DbModel::outside(const std::array<double, 3>& domain_m) const {
  std::string sides;
  for (int a = 0; a < 3; ++a) {
    if (info_.extent_m[a] == 0) continue;
    const double lo = info_.origin_m[a], hi = lo + info_.extent_m[a];
    const double slack = 1e-9 * std::max(std::abs(hi), domain_m[a]);
    char buf[128];
    if (lo > slack) {
      std::snprintf(buf, sizeof buf, "%s%c below %g m", sides.empty() ? "" : ", ", kAxes[a], lo);
      sides += buf;
    }
    if (domain_m[a] > hi + slack) {
      std::snprintf(buf, sizeof buf, "%s%c past %g m (to %g)", sides.empty() ? "" : ", ", kAxes[a],
                    hi, domain_m[a]);
      sides += buf;
    }
  }
  return sides.empty() ? "" : "the domain reaches outside the model's box: " + sides;
}

Status DbModel::hole_at(double x, double y, double z) const {
  char buf[160];
  std::snprintf(buf, sizeof buf, "the model has no octant at (%g, %g, %g) m", x, y, z);
  return Status::NotFound(buf);
}

bool DbModel::focus(const double lo[3], const double hi[3]) const {
  Reader& r = reader();
  if (!r.opened.ok()) return true;  // each point reports the error
  bool clamped = false;
  const Coord a = pixel_of(lo[0], lo[1], lo[2], &clamped);
  const Coord b = pixel_of(hi[0], hi[1], hi[2], &clamped);
  // A box inside the region loaded keeps it: its answers are the table's
  // wherever it holds the point, so a larger one changes none of them.
  // (Construct's balance asks a box inside the one its descent asked: see
  // Descent::visit_subtree.)
  if (r.region.covers(a) && r.region.covers(b)) return true;
  // On a read error the region stays empty and the table answers (and
  // reports the error) point by point; a smaller box would fail alike.
  if (!r.region.load(*r.table, a, b, r.table->options().schema.record_size(), region_octants_)
           .ok()) {
    r.region.clear();
    return true;
  }
  return r.region.loaded();  // false: more octants than its room
}

Coord DbModel::pixel_of(double x, double y, double z, bool* clamped) const {
  *clamped = false;
  return {pixel_on(0, x, clamped), pixel_on(1, y, clamped), pixel_on(2, z, clamped)};
}

Status DbModel::find(Reader& r, double x, double y, double z, ModelHit* hit) const {
  bool clamped = false;
  const Coord t = pixel_of(x, y, z, &clamped);
  return find_pixel(r, t, clamped, x, y, z, hit);
}

// (x, y, z) name the point in a hole's error.
Status DbModel::find_pixel(Reader& r, Coord t, bool clamped, double x, double y, double z,
                           ModelHit* hit) const {
  WEAVER_RETURN_IF_ERROR(r.opened);
  hit->clamped = clamped;
  if (r.region.covers(t)) {
    const int32_t i = r.region.find(t);
    if (i == ModelRegion::kHole) return hole_at(x, y, z);
    hit->values = r.region.values(i);
    hit->octant = r.region.octant(i);
    return Status::Ok();
  }
  if (!r.last.holds(t)) {
    Reader::Found& f = r.seen_slot(t);
    if (!f.holds(t)) {
      uint64_t key = 0;
      bool found = false;
      std::byte payload[sizeof(ModelValues)] = {};
      WEAVER_RETURN_IF_ERROR(r.table->floor(pixel_key(t), &key, payload, &found));
      const Octant o = found ? octant_from_key(key) : Octant{};
      if (!found || !octant_contains_point(o, t)) return hole_at(x, y, z);
      std::memcpy(f.values.data(), payload, r.table->options().schema.record_size());
      f.octant = o;
      f.lo = octant_corner(o);
      f.edge = octant_edge(o);
    }
    r.last = f;
  }
  hit->values = r.last.values;
  hit->octant = r.last.octant;
  return Status::Ok();
}

Status DbModel::lookup(double x, double y, double z, ModelHit* hit) const {
  return find(reader(), x, y, z, hit);
}

Status DbModel::lookup_batch(const double* xyz, size_t n, ModelHit* hits) const {
  Reader& r = reader();
  struct Ask {
    uint64_t code;  // the pixel's Morton code: the order answered in
    uint32_t point;
    Coord pixel;
    bool clamped;
  };
  std::vector<Ask> order(n);
  for (size_t i = 0; i < n; ++i) {
    const double* p = xyz + 3 * i;
    Ask& a = order[i];
    a.pixel = pixel_of(p[0], p[1], p[2], &a.clamped);
    a.code = morton_encode(a.pixel);
    a.point = static_cast<uint32_t>(i);
  }
  std::sort(order.begin(), order.end(), [](const Ask& a, const Ask& b) { return a.code < b.code; });
  for (const Ask& a : order) {
    const double* p = xyz + 3 * size_t{a.point};
    WEAVER_RETURN_IF_ERROR(find_pixel(r, a.pixel, a.clamped, p[0], p[1], p[2], &hits[a.point]));
  }
  return Status::Ok();
}

Material DbModel::at(double x, double y, double z) const {
  ModelHit h;
  // A hole in the model: the point takes no material (construct refuses
  // nothing here; the octant's Vs of 0 asks for the finest leaves).
  if (!lookup(x, y, z, &h).ok()) return {};
  return {h.values[0], h.values[1], h.values[2], h.values[3], h.values[4]};
}

// From the focused region where it holds the lattice (construct's case):
// the pixels and raster cells of each axis once, then a load or two a point.
// A lattice reaching outside the region (the octants around a subtree,
// judged by its balance) takes the points outside it from the table.
template <class Put>
void DbModel::each_on_lattice(const double* xs, const double* ys, const double* zs, int n,
                              const Put& put) const {
  Reader& r = reader();
  const ModelRegion& g = r.region;
  uint32_t px[kLatticeMost], py[kLatticeMost], pz[kLatticeMost];
  uint32_t cx[kLatticeMost], cy[kLatticeMost], cz[kLatticeMost];
  bool clamped_x[kLatticeMost], clamped_y[kLatticeMost], clamped_z[kLatticeMost];
  bool covered = g.loaded();
  for (int i = 0; i < n; ++i) {
    clamped_x[i] = clamped_y[i] = clamped_z[i] = false;
    px[i] = pixel_on(0, xs[i], &clamped_x[i]);
    py[i] = pixel_on(1, ys[i], &clamped_y[i]);
    pz[i] = pixel_on(2, zs[i], &clamped_z[i]);
    covered = covered && g.covers({px[i], py[i], pz[i]});
    if (g.loaded()) cx[i] = g.cell_x(px[i]), cy[i] = g.cell_y(py[i]), cz[i] = g.cell_z(pz[i]);
  }
  if (covered) return put.whole(g, ModelRegion::Lattice{{px, py, pz}, {cx, cy, cz}, n});
  ModelHit h;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const Coord p{px[i], py[j], pz[k]};
        const int index = (k * n + j) * n + i;
        if (g.covers(p)) {
          put.in_region(g, index, p, cx[i], cy[j], cz[k]);
        } else {
          const bool clamped = clamped_x[i] || clamped_y[j] || clamped_z[k];
          put(index, find_pixel(r, p, clamped, xs[i], ys[j], zs[k], &h).ok() ? &h.values : nullptr);
        }
      }
}

namespace {

// each_on_lattice's answers as Vs: a point in the region from its cell's Vs
// range where that is one value (ModelRegion::vs_at).
struct PutVs {
  float* out;
  void whole(const ModelRegion& g, const ModelRegion::Lattice& l) const { g.vs_on_lattice(l, out); }
  void in_region(const ModelRegion& g, int index, Coord p, uint32_t cx, uint32_t cy,
                 uint32_t cz) const {
    out[index] = g.vs_at(p, cx, cy, cz);
  }
  void operator()(int index, const ModelValues* v) const {
    out[index] = v != nullptr ? (*v)[1] : 0.0f;
  }
};

// ... and as materials: every value of the octant holding the point.
struct PutMaterials {
  Material* out;
  void whole(const ModelRegion& g, const ModelRegion::Lattice& l) const {
    int32_t
        found[ModelRegion::kLatticeMost * ModelRegion::kLatticeMost * ModelRegion::kLatticeMost];
    g.find_on_lattice(l, found);
    const int points = l.n * l.n * l.n;
    for (int i = 0; i < points; ++i) {
      (*this)(i, found[i] == ModelRegion::kHole ? nullptr : &g.values(found[i]));
    }
  }
  void in_region(const ModelRegion& g, int index, Coord p, uint32_t cx, uint32_t cy,
                 uint32_t cz) const {
    const int32_t o = g.find(p, cx, cy, cz);
    (*this)(index, o == ModelRegion::kHole ? nullptr : &g.values(o));
  }
  void operator()(int index, const ModelValues* v) const {
    out[index] = v != nullptr ? Material{(*v)[0], (*v)[1], (*v)[2], (*v)[3], (*v)[4]} : Material{};
  }
};

}  // namespace

void DbModel::vs_on_lattice(const double* xs, const double* ys, const double* zs, int n,
                            float* out) const {
  if (n > kLatticeMost) {
    Reader& r = reader();
    ModelHit h;
    for (int k = 0; k < n; ++k)
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
          out[(k * n + j) * n + i] = find(r, xs[i], ys[j], zs[k], &h).ok() ? h.values[1] : 0.0f;
        }
    return;
  }
  each_on_lattice(xs, ys, zs, n, PutVs{out});
}

// The values at()'s lookup finds (a hole: no material), a lattice at a time:
// construct's eight sibling leaves, whose centres' pixels were found point by
// point (a tenth of a construct from a model database).
void DbModel::materials_on_lattice(const double* xs, const double* ys, const double* zs, int n,
                                   Material* out) const {
  if (n > kLatticeMost) return VelocityModel::materials_on_lattice(xs, ys, zs, n, out);
  each_on_lattice(xs, ys, zs, n, PutMaterials{out});
}

// at() of a point of the box finds its pixel in [pixel(lo), pixel(hi)]
// (pixel_on is monotone), so the region's bounds over those pixels hold.
bool DbModel::vs_bounds(const double lo[3], const double hi[3], float* vs_lo, float* vs_hi) const {
  Reader& r = reader();
  if (!r.opened.ok()) return false;
  bool clamped = false;
  return r.region.vs_bounds(pixel_of(lo[0], lo[1], lo[2], &clamped),
                            pixel_of(hi[0], hi[1], hi[2], &clamped), vs_lo, vs_hi);
}

void DbModel::vs_bounds_of_eighths(const double edges[3][3], const bool want[8], float vs_lo[8],
                                   float vs_hi[8], bool ok[8]) const {
  Reader& r = reader();
  bool clamped = false;
  uint32_t pixel[3][3];  // by axis and coordinate (pixel_of's, an axis at a time)
  for (int a = 0; a < 3; ++a) {
    for (int t = 0; t < 3; ++t) pixel[a][t] = pixel_on(a, edges[a][t], &clamped);
  }
  for (int c = 0; c < 8; ++c) {
    if (!want[c]) continue;
    const int b[3] = {c & 1, (c >> 1) & 1, (c >> 2) & 1};
    const Coord lo{pixel[0][b[0]], pixel[1][b[1]], pixel[2][b[2]]};
    const Coord hi{pixel[0][b[0] + 1], pixel[1][b[1] + 1], pixel[2][b[2] + 1]};
    ok[c] = r.opened.ok() && r.region.vs_bounds(lo, hi, &vs_lo[c], &vs_hi[c]);
  }
}

std::string DbModel::describe() const {
  return "model database " + dir_ + " (" + info_.source + ", " + std::to_string(octants_) +
         " octants)";
}

}  // namespace weaver
