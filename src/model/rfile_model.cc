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
};

namespace {

std::atomic<uint64_t> next_serial{1};

uint64_t column_tag(int b, int i, int j) {
  return ((uint64_t(b) << 50) | (uint64_t(i) << 25) | uint64_t(j)) + 1;
}

size_t column_slot(uint64_t tag, size_t slots) {
  return static_cast<size_t>((tag * 0x9E3779B97F4A7C15ull) >> 20) & (slots - 1);
}

int clamp_index(double v, int last) {
  // SW4: trunc(1 + v) on 1-based indices, then at least the first point and
  // at most the last but one (the cell's far point is the last).
  const double t = std::trunc(v);
  if (!(t > 0)) return 0;
  return t >= last - 1 ? last - 1 : static_cast<int>(t);
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
  std::vector<double> col(size_t(k.nk) * k.nc);
  for (int i = 0; i < k.ni; ++i) {
    for (int j = 0; j < k.nj; ++j) {
      WEAVER_RETURN_IF_ERROR(read_rfile_column(m->fd_, m->h_, last, i, j, col.data()));
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

// Reads the column and fills its no-data levels as SW4 does: from the first
// valid level below; a column without one from the top of the block below.
Status RfileModel::load_column(Cache& c, int b, int i, int j, double* out) const {
  const RfileBlock& k = h_.blocks[b];
  const int nc = k.nc;
  WEAVER_RETURN_IF_ERROR(read_rfile_column(fd_, h_, b, i, j, out));
  int k0 = 0;
  while (out[size_t(k0) * nc + 2] == kRfileNoData && k0 < k.nk - 1) ++k0;
  if (out[size_t(k0) * nc + 2] == kRfileNoData) {
    // Only the bottom block could lack a donor, and open() refused that.
    const int d = b + 1;
    const RfileBlock& dk = h_.blocks[d];
    const int id = std::min(dk.ni - 1, static_cast<int>(std::trunc(i * k.hh / dk.hh)));
    const int jd = std::min(dk.nj - 1, static_cast<int>(std::trunc(j * k.hh / dk.hh)));
    double top[5];
    const double* donor = column(c, d, id, jd);
    std::memcpy(top, donor, sizeof(double) * size_t(nc));
    std::memcpy(out + size_t(k0) * nc, top, sizeof(double) * size_t(nc));
  }
  for (int z = 0; z < k0; ++z)
    std::memcpy(out + size_t(z) * nc, out + size_t(k0) * nc, sizeof(double) * size_t(nc));
  return Status::Ok();
}

const double* RfileModel::column(Cache& c, int b, int i, int j) const {
  const uint64_t tag = column_tag(b, i, j);
  const size_t s = column_slot(tag, slots_);
  double* slot = c.values.data() + s * stride_;
  if (c.tags[s] == tag) return slot;
  // Filled in a scratch column of its own: the donor's column may take
  // this very slot.
  std::vector<double> own(size_t(h_.blocks[b].nk) * h_.blocks[b].nc);
  const Status st = load_column(c, b, i, j, own.data());
  if (!st.ok()) {
    fail(st);
    std::fill(own.begin(), own.end(), 0.0);
    c.tags[s] = 0;
    std::memcpy(c.scratch.data(), own.data(), own.size() * sizeof(double));
    return c.scratch.data();
  }
  std::memcpy(slot, own.data(), own.size() * sizeof(double));
  c.tags[s] = tag;
  return slot;
}

RfileModel::Cell RfileModel::cell_of(double x, double y, double z) const {
  x = std::clamp(x, 0.0, x_extent());
  y = std::clamp(y, 0.0, y_extent());
  z = std::clamp(z, z_top(), z_bottom());
  int gr = int(h_.blocks.size()) - 1;
  while (gr >= 1 && z < h_.blocks[gr].z0) --gr;
  if (gr == 0) gr = 1;
  const RfileBlock& k = h_.blocks[gr];
  Cell c;
  c.block = gr;
  c.i0 = clamp_index(x / k.hh, k.ni - 1);
  c.j0 = clamp_index(y / k.hh, k.nj - 1);
  c.k0 = clamp_index((z - k.z0) / k.hv, k.nk - 1);
  c.wx = (x - c.i0 * k.hh) / k.hh;
  c.wy = (y - c.j0 * k.hh) / k.hh;
  c.wz = (z - (c.k0 * k.hv + k.z0)) / k.hv;
  return c;
}

float RfileModel::vs_at(double x, double y, double z) const {
  const Cell cell = cell_of(x, y, z);
  const int nc = h_.blocks[cell.block].nc;
  double v[2][2][2];
  Cache& c = cache();
  for (int di = 0; di < 2; ++di) {
    for (int dj = 0; dj < 2; ++dj) {
      const double* col = column(c, cell.block, cell.i0 + di, cell.j0 + dj) + size_t(cell.k0) * nc;
      v[di][dj][0] = col[2], v[di][dj][1] = col[nc + 2];
    }
  }
  const double wx = cell.wx, wy = cell.wy, wz = cell.wz;
  const auto lerp_x = [&](int dj, int dk) { return (1 - wx) * v[0][dj][dk] + wx * v[1][dj][dk]; };
  return float((1 - wz) * ((1 - wy) * lerp_x(0, 0) + wy * lerp_x(1, 0)) +
               wz * ((1 - wy) * lerp_x(0, 1) + wy * lerp_x(1, 1)));
}

Material RfileModel::at(double x, double y, double z) const {
  const Cell cell = cell_of(x, y, z);
  const int gr = cell.block, i0 = cell.i0, j0 = cell.j0, k0 = cell.k0;
  const double wx = cell.wx, wy = cell.wy, wz = cell.wz;
  const int nc = h_.blocks[gr].nc;
  // v[di][dj][dk][component], copied out at once: the next column may
  // take the slot of this one.
  double v[2][2][2][5];
  Cache& c = cache();
  for (int di = 0; di < 2; ++di) {
    for (int dj = 0; dj < 2; ++dj) {
      const double* col = column(c, gr, i0 + di, j0 + dj) + size_t(k0) * nc;
      for (int dk = 0; dk < 2; ++dk)
        std::memcpy(v[di][dj][dk], col + size_t(dk) * nc, sizeof(double) * size_t(nc));
    }
  }
  double r[5] = {0, 0, 0, 0, 0};
  for (int f = 0; f < nc; ++f) {
    const auto lerp_x = [&](int dj, int dk) {
      return (1 - wx) * v[0][dj][dk][f] + wx * v[1][dj][dk][f];
    };
    r[f] = (1 - wz) * ((1 - wy) * lerp_x(0, 0) + wy * lerp_x(1, 0)) +
           wz * ((1 - wy) * lerp_x(0, 1) + wy * lerp_x(1, 1));
  }
  // rho, vp, vs [, qp, qs] in the file; Material is vp, vs, rho, qp, qs.
  return Material{float(r[1]), float(r[2]), float(r[0]), float(r[3]), float(r[4])};
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
