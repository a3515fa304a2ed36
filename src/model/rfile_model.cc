#include "model/rfile_model.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>

#include "model/geo_frame.h"

namespace weaver {

struct RfileModel::Cache {
  std::vector<uint64_t> tags;  // block, i, j of each slot, plus one; 0: empty
  std::vector<double> values;  // slots x stride
  std::vector<double> scratch;
  // A run of columns' bytes as read, a buffer a block: filling one may look
  // up the block below's (whose own run then goes to its own buffer).
  std::vector<std::vector<unsigned char>> runs;
  std::vector<double> lattice;  // lattice_in_block's columns
};

namespace {

std::atomic<uint64_t> next_serial{1};

uint64_t column_tag(int b, int i, int j) {
  return ((uint64_t(b) << 50) | (uint64_t(i) << 25) | uint64_t(j)) + 1;
}

size_t column_slot(uint64_t tag, size_t slots) {
  return static_cast<size_t>((tag * 0x9E3779B97F4A7C15ull) >> 20) & (slots - 1);
}

// Columns a miss reads at once along j (they lie one after another).
constexpr int kRunColumns = 16;

// The trilinear value in a cell as SW4 weighs it: p[di][dj] the column of
// corner (di, dj), its two levels nc values apart (rho, vp, vs [, qp, qs]);
// Material's order out.  NC a constant, so the components unroll.
template <int NC>
Material blend_of(const double* const (&p)[2][2], double wx, double wy, double wz) {
  double r[5] = {0, 0, 0, 0, 0};
  for (int f = 0; f < NC; ++f) {
    const auto lerp_x = [&](int dj, int dk) {
      return (1 - wx) * p[0][dj][dk * NC + f] + wx * p[1][dj][dk * NC + f];
    };
    r[f] = (1 - wz) * ((1 - wy) * lerp_x(0, 0) + wy * lerp_x(1, 0)) +
           wz * ((1 - wy) * lerp_x(0, 1) + wy * lerp_x(1, 1));
  }
  // rho, vp, vs [, qp, qs] in the file; Material is vp, vs, rho, qp, qs.
  return Material{float(r[1]), float(r[2]), float(r[0]), float(r[3]), float(r[4])};
}

Material blend(const double* const (&p)[2][2], int nc, double wx, double wy, double wz) {
  return nc == 5 ? blend_of<5>(p, wx, wy, wz) : blend_of<3>(p, wx, wy, wz);
}

}  // namespace

Status RfileModel::open(const std::string& path, MemoryBudget memory, int threads,
                        std::unique_ptr<RfileModel>* out) {
  std::unique_ptr<RfileModel> m(new RfileModel());
  m->path_ = path;
  WEAVER_RETURN_IF_ERROR(read_rfile_header(path, &m->h_));
  m->fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (m->fd_ < 0) return Status::IOError(path + ": " + std::strerror(errno));
  for (size_t b = 1; b < m->h_.blocks.size(); ++b) {
    const RfileBlock& k = m->h_.blocks[b];
    m->stride_ = std::max(m->stride_, size_t(k.nk) * k.nc);
  }
  const uint64_t per_thread = memory.bytes() / uint64_t(std::max(1, threads));
  const uint64_t slot_bytes = m->stride_ * sizeof(double) + sizeof(uint64_t);
  m->slots_ = 64;
  while (m->slots_ * 2 * slot_bytes <= per_thread && m->slots_ < (size_t{1} << 24)) m->slots_ *= 2;
  m->serial_ = next_serial.fetch_add(1);
  // A column of the bottom block with no valid Vs has nothing below to take
  // from: SW4 reports it as an error, and so do we, before any sampling.
  const int last = int(m->h_.blocks.size()) - 1;
  const RfileBlock& k = m->h_.blocks[last];
  // Read in runs of columns along j (one read each), within 8 MB.
  const size_t per = size_t(k.nk) * k.nc;
  const int run = int(std::clamp<size_t>((size_t{1} << 20) / per, 1, size_t(k.nj)));
  std::vector<double> cols(per * size_t(run));
  for (int i = 0; i < k.ni; ++i) {
    for (int j = 0; j < k.nj; ++j) {
      const int q = j % run;
      if (q == 0) {
        WEAVER_RETURN_IF_ERROR(
            read_rfile_columns(m->fd_, m->h_, last, i, j, std::min(run, k.nj - j), cols.data()));
      }
      const double* col = cols.data() + per * size_t(q);
      bool any = false;
      for (int z = 0; z < k.nk && !any; ++z) any = col[size_t(z) * k.nc + 2] != kRfileNoData;
      if (!any) {
        char buf[160];
        std::snprintf(buf, sizeof buf,
                      ": the bottom block's column i=%d j=%d has no data (-999) at every level, "
                      "and nothing below to fill it from",
                      i, j);
        return Status::Corruption(path + buf);
      }
    }
  }
  *out = std::move(m);
  return Status::Ok();
}

RfileModel::~RfileModel() {
  if (fd_ >= 0) ::close(fd_);
}

RfileModel::Cache& RfileModel::cache() const {
  thread_local const RfileModel* owner = nullptr;
  thread_local uint64_t owner_serial = 0;
  thread_local Cache* cached = nullptr;
  if (owner == this && owner_serial == serial_) return *cached;
  std::lock_guard<std::mutex> lock(mu_);
  auto& c = caches_[std::this_thread::get_id()];
  if (!c) {
    c = std::make_unique<Cache>();
    c->tags.assign(slots_, 0);
    c->values.resize(slots_ * stride_);
    c->scratch.resize(stride_);
  }
  owner = this, owner_serial = serial_, cached = c.get();
  return *c;
}

void RfileModel::fail(const Status& s) const {
  std::lock_guard<std::mutex> lock(mu_);
  if (!failed_.exchange(true)) error_ = s;
}

Status RfileModel::error() const {
  if (!failed_.load()) return Status::Ok();
  std::lock_guard<std::mutex> lock(mu_);
  return error_;
}

// Fills the column's no-data levels as SW4 does: from the first valid level
// below; a column without one from the top of the block below.
void RfileModel::fill_column(Cache& c, int b, int i, int j, double* out) const {
  const RfileBlock& k = h_.blocks[b];
  const int nc = k.nc;
  int k0 = 0;
  while (out[size_t(k0) * nc + 2] == kRfileNoData && k0 < k.nk - 1) ++k0;
  if (out[size_t(k0) * nc + 2] == kRfileNoData) {
    // Only the bottom block could lack a donor, and open() refused that.
    // The donor's lookup may take out's slot: its values are taken first,
    // and out is all written after (k0 is its last level here).
    const int d = b + 1;
    const RfileBlock& dk = h_.blocks[d];
    const int id = std::min(dk.ni - 1, static_cast<int>(std::trunc(i * k.hh / dk.hh)));
    const int jd = std::min(dk.nj - 1, static_cast<int>(std::trunc(j * k.hh / dk.hh)));
    double top[5];
    std::memcpy(top, column(c, d, id, jd), sizeof(double) * size_t(nc));
    std::memcpy(out + size_t(k0) * nc, top, sizeof(double) * size_t(nc));
  }
  for (int z = 0; z < k0; ++z)
    std::memcpy(out + size_t(z) * nc, out + size_t(k0) * nc, sizeof(double) * size_t(nc));
}

const double* RfileModel::column(Cache& c, int b, int i, int j) const {
  const uint64_t tag = column_tag(b, i, j);
  const size_t s = column_slot(tag, slots_);
  if (c.tags[s] == tag) return c.values.data() + s * stride_;
  // A miss reads its run of columns from j on in one read and decodes each
  // into its slot, where it is filled; the asked one last, so that its slot
  // holds it (a donor's lookup, or a later column of the run, may take any
  // slot meanwhile).
  const RfileBlock& k = h_.blocks[b];
  const int count = std::min(kRunColumns, k.nj - j);
  const size_t per = size_t(k.nk) * k.nc;
  if (c.runs.size() < h_.blocks.size()) c.runs.resize(h_.blocks.size());
  std::vector<unsigned char>& run = c.runs[b];
  const Status st = read_rfile_raw(fd_, h_, b, i, j, count, &run);
  if (!st.ok()) {
    fail(st);
    std::fill(c.scratch.begin(), c.scratch.end(), 0.0);
    return c.scratch.data();
  }
  for (int q = count - 1; q >= 0; --q) {
    const uint64_t tag_q = column_tag(b, i, j + q);
    const size_t s_q = column_slot(tag_q, slots_);
    double* col = c.values.data() + s_q * stride_;
    rfile_decode(h_.precision, run.data() + per * size_t(q) * h_.precision, per, col);
    fill_column(c, b, i, j + q, col);
    c.tags[s_q] = tag_q;
  }
  return c.values.data() + s * stride_;
}

int RfileModel::block_of(double z) const {
  int gr = int(h_.blocks.size()) - 1;
  while (gr >= 1 && z < h_.blocks[gr].z0) --gr;
  return gr == 0 ? 1 : gr;
}

RfileModel::Cell RfileModel::cell_of(double x, double y, double z) const {
  x = std::clamp(x, 0.0, x_extent());
  y = std::clamp(y, 0.0, y_extent());
  z = std::clamp(z, z_top(), z_bottom());
  Cell c;
  c.block = block_of(z);
  const RfileBlock& k = h_.blocks[c.block];
  const RfilePlace px = rfile_place(x, 0, k.hh, k.ni), py = rfile_place(y, 0, k.hh, k.nj);
  const RfilePlace pz = rfile_place(z, k.z0, k.hv, k.nk);
  c.i0 = px.i, c.j0 = py.i, c.k0 = pz.i;
  c.wx = px.w, c.wy = py.w, c.wz = pz.w;
  return c;
}

namespace {

// Vs at one point of a cell from its corners' values v[di][dj][dk], SW4's
// trilinear weights.
float vs_in_cell(const double (&v)[2][2][2], double wx, double wy, double wz) {
  const auto lerp_x = [&](int dj, int dk) { return (1 - wx) * v[0][dj][dk] + wx * v[1][dj][dk]; };
  return float((1 - wz) * ((1 - wy) * lerp_x(0, 0) + wy * lerp_x(1, 0)) +
               wz * ((1 - wy) * lerp_x(0, 1) + wy * lerp_x(1, 1)));
}

// A cell's corner Vs (component 2) at levels k0 and k0 + 1 of its corner
// columns of nc components.
void corner_vs(const double* const (&cols)[2][2], int nc, int k0, double (&v)[2][2][2]) {
  for (int di = 0; di < 2; ++di) {
    for (int dj = 0; dj < 2; ++dj) {
      const double* col = cols[di][dj] + size_t(k0) * nc;
      v[di][dj][0] = col[2], v[di][dj][1] = col[nc + 2];
    }
  }
}

}  // namespace

float RfileModel::vs_at(double x, double y, double z) const {
  const Cell cell = cell_of(x, y, z);
  const int nc = h_.blocks[cell.block].nc;
  Cache& c = cache();
  double v[2][2][2];
  for (int di = 0; di < 2; ++di) {
    for (int dj = 0; dj < 2; ++dj) {
      // Taken before the next lookup can evict the column.
      const double* col = column(c, cell.block, cell.i0 + di, cell.j0 + dj) + size_t(cell.k0) * nc;
      v[di][dj][0] = col[2], v[di][dj][1] = col[nc + 2];
    }
  }
  return vs_in_cell(v, cell.wx, cell.wy, cell.wz);
}

// The four corner columns of the cell from (i0, j0) of block b, all still
// in the cache once looked up (a miss may take a slot one of the others
// held): false then, and the caller samples point by point.
bool RfileModel::corner_columns(Cache& c, int b, int i0, int j0,
                                const double* (&cols)[2][2]) const {
  for (int di = 0; di < 2; ++di)
    for (int dj = 0; dj < 2; ++dj) cols[di][dj] = column(c, b, i0 + di, j0 + dj);
  for (int di = 0; di < 2; ++di) {
    for (int dj = 0; dj < 2; ++dj) {
      const uint64_t tag = column_tag(b, i0 + di, j0 + dj);
      const size_t s = column_slot(tag, slots_);
      if (c.tags[s] != tag || cols[di][dj] != c.values.data() + s * stride_) return false;
    }
  }
  return true;
}

// A column's points share their place across and, while in one block, the
// four corner columns: vs_at's arithmetic, to the bit, placed once.
void RfileModel::vs_on_columns(const double* xs, const double* ys, const double* zs, int n,
                               float* out) const {
  Cache& c = cache();
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const double x = std::clamp(xs[i], 0.0, x_extent()), y = std::clamp(ys[j], 0.0, y_extent());
      const double* column_z = zs + (j * n + i) * n;
      int block = -1, nc = 0;
      bool shared = false;
      RfilePlace px{}, py{};
      const double* cols[2][2] = {};
      for (int k = 0; k < n; ++k) {
        const double z = std::clamp(column_z[k], z_top(), z_bottom());
        const int b = block_of(z);
        const RfileBlock& blk = h_.blocks[b];
        if (b != block) {
          block = b, nc = blk.nc;
          px = rfile_place(x, 0, blk.hh, blk.ni), py = rfile_place(y, 0, blk.hh, blk.nj);
          shared = corner_columns(c, b, px.i, py.i, cols);
        }
        float& v = out[(k * n + j) * n + i];
        if (!shared) {
          v = vs_at(x, y, z);
          continue;
        }
        const RfilePlace pz = rfile_place(z, blk.z0, blk.hv, blk.nk);
        double corners[2][2][2];
        corner_vs(cols, nc, pz.i, corners);
        v = vs_in_cell(corners, px.w, py.w, pz.w);
      }
    }
  }
}

void RfileModel::vs_on_lattice(const double* xs, const double* ys, const double* zs, int n,
                               float* out) const {
  if (n > kLatticeMost) return VelocityModel::vs_on_lattice(xs, ys, zs, n, out);
  double columns[kLatticeMost * kLatticeMost * kLatticeMost];
  lattice_as_columns(zs, n, columns);
  vs_on_columns(xs, ys, columns, n, out);
}

bool RfileModel::vs_bounds(const double lo[3], const double hi[3], float* vs_lo,
                           float* vs_hi) const {
  std::call_once(tiles_once_, [&] {
    Cache& c = cache();
    tiles_.build(h_, [&](int b, int i, int j) { return column(c, b, i, j); });
  });
  if (failed_) return false;  // the error is reported where sampling meets it
  return tiles_.bounds(h_, lo, hi, vs_lo, vs_hi);
}

Material RfileModel::at(double x, double y, double z) const {
  const Cell cell = cell_of(x, y, z);
  const int gr = cell.block, i0 = cell.i0, j0 = cell.j0, k0 = cell.k0;
  const int nc = h_.blocks[gr].nc;
  // Copied out at once: the next column may take the slot of this one.
  double v[2][2][10];
  const double* p[2][2];
  Cache& c = cache();
  for (int di = 0; di < 2; ++di) {
    for (int dj = 0; dj < 2; ++dj) {
      const double* col = column(c, gr, i0 + di, j0 + dj) + size_t(k0) * nc;
      std::memcpy(v[di][dj], col, sizeof(double) * size_t(2 * nc));
      p[di][dj] = v[di][dj];
    }
  }
  return blend(p, nc, cell.wx, cell.wy, cell.wz);
}

void RfileModel::lattice_at(const double* xs, int nx, const double* ys, int ny, const double* zs,
                            int nz, Material* out) const {
  Cache& c = cache();
  // The z's in one block at a time (ascending: the blocks follow in turn).
  for (int z0 = 0; z0 < nz;) {
    const int b = block_of(std::clamp(zs[z0], z_top(), z_bottom()));
    int z1 = z0 + 1;
    while (z1 < nz && block_of(std::clamp(zs[z1], z_top(), z_bottom())) == b) ++z1;
    lattice_in_block(c, b, xs, nx, ys, ny, zs + z0, z1 - z0, out + size_t(z0) * ny * nx);
    z0 = z1;
  }
}

void RfileModel::lattice_in_block(Cache& c, int b, const double* xs, int nx, const double* ys,
                                  int ny, const double* zs, int nz, Material* out) const {
  const RfileBlock& k = h_.blocks[b];
  const int nc = k.nc;
  std::vector<RfilePlace> px(nx), py(ny), pz(nz);
  for (int a = 0; a < nx; ++a)
    px[a] = rfile_place(std::clamp(xs[a], 0.0, x_extent()), 0, k.hh, k.ni);
  for (int a = 0; a < ny; ++a)
    py[a] = rfile_place(std::clamp(ys[a], 0.0, y_extent()), 0, k.hh, k.nj);
  for (int a = 0; a < nz; ++a) {
    pz[a] = rfile_place(std::clamp(zs[a], z_top(), z_bottom()), k.z0, k.hv, k.nk);
  }
  // Ascending points: the first and last cells bound the columns and levels.
  const int i_lo = px[0].i, ni = px[nx - 1].i + 2 - i_lo;
  const int j_lo = py[0].i, nj = py[ny - 1].i + 2 - j_lo;
  const int k_lo = pz[0].i, nk = pz[nz - 1].i + 2 - k_lo;
  std::vector<double>& local = c.lattice;  // [i][j][k][component]
  local.resize(size_t(ni) * nj * nk * nc);
  for (int i = 0; i < ni; ++i) {
    for (int j = 0; j < nj; ++j) {
      const double* col = column(c, b, i_lo + i, j_lo + j) + size_t(k_lo) * nc;
      std::memcpy(&local[(size_t(i) * nj + j) * nk * nc], col, sizeof(double) * nk * nc);
    }
  }
  const auto at_local = [&](int i, int j, int kk) {
    return &local[((size_t(i - i_lo) * nj + (j - j_lo)) * nk + (kk - k_lo)) * nc];
  };
  const double* p[2][2];
  for (int cz = 0; cz < nz; ++cz) {
    for (int cy = 0; cy < ny; ++cy) {
      for (int cx = 0; cx < nx; ++cx) {
        for (int di = 0; di < 2; ++di) {
          for (int dj = 0; dj < 2; ++dj) {
            p[di][dj] = at_local(px[cx].i + di, py[cy].i + dj, pz[cz].i);
          }
        }
        out[(size_t(cz) * ny + cy) * nx + cx] = blend(p, nc, px[cx].w, py[cy].w, pz[cz].w);
      }
    }
  }
}

std::string RfileModel::outside(const std::array<double, 3>& domain_m) const {
  std::string sides;
  const auto add = [&](const char* s) { sides += sides.empty() ? s : std::string(", ") + s; };
  if (domain_m[0] > x_extent() * (1 + 1e-9)) add("x+");
  if (domain_m[1] > y_extent() * (1 + 1e-9)) add("y+");
  if (domain_m[2] > z_bottom() * (1 + 1e-9)) add("z+ (below the bottom block)");
  if (sides.empty()) return "";
  char buf[200];
  std::snprintf(buf, sizeof buf, " (the rfile spans %g x %g m, z %g to %g m)", x_extent(),
                y_extent(), z_top(), z_bottom());
  return "the domain reaches past the rfile " + path_ + " on " + sides + buf;
}

std::string RfileModel::geo() const {
  GeoFrame g;
  g.lon0 = h_.lon0, g.lat0 = h_.lat0, g.azimuth = h_.azimuth;
  return g.to_text();
}

std::string RfileModel::describe() const {
  char buf[200];
  std::snprintf(buf, sizeof buf, "rfile %s: %zu material blocks, hh %g to %g m, %s", path_.c_str(),
                h_.blocks.size() - 1, h_.blocks[1].hh, h_.blocks.back().hh,
                h_.has_q() ? "rho, vp, vs, qp, qs" : "rho, vp, vs");
  return buf;
}

}  // namespace weaver
