#include "model/grid_model.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <vector>

namespace weaver {
namespace {

constexpr char kMagic[] = "weaver-grid 1";  // do not change: file format

class GridModel final : public VelocityModel {
 public:
  GridModel(GridSpec spec, std::vector<Material> values, std::string path)
      : s_(spec), v_(std::move(values)), path_(std::move(path)) {}

  Material at(double x, double y, double z) const override {
    int i, j, k;
    double fx, fy, fz;
    locate(x, s_.x0, s_.dx, s_.nx, &i, &fx);
    locate(y, s_.y0, s_.dy, s_.ny, &j, &fy);
    locate(z, s_.z0, s_.dz, s_.nz, &k, &fz);
    double out[3] = {0, 0, 0};
    for (int c = 0; c < 8; ++c) {
      const double w = ((c & 1) ? fx : 1 - fx) * ((c & 2) ? fy : 1 - fy) * ((c & 4) ? fz : 1 - fz);
      const Material& m = v_[index(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1))];
      out[0] += w * m.vp;
      out[1] += w * m.vs;
      out[2] += w * m.rho;
    }
    return {float(out[0]), float(out[1]), float(out[2])};
  }

  std::string describe() const override {
    char buf[300];
    std::snprintf(buf, sizeof buf, "grid %s: %d x %d x %d points, spacing %g x %g x %g m",
                  path_.c_str(), s_.nx, s_.ny, s_.nz, s_.dx, s_.dy, s_.dz);
    return buf;
  }

 private:
  // The cell [i, i+1] holding coordinate c, and the fraction within it
  // (clamped to the grid).
  static void locate(double c, double origin, double step, int n, int* i, double* f) {
    double t = std::clamp((c - origin) / step, 0.0, double(n - 1));
    *i = std::min(static_cast<int>(t), n - 2);
    *f = t - *i;
  }
  size_t index(int i, int j, int k) const { return (size_t(k) * s_.ny + j) * s_.nx + i; }

  GridSpec s_;
  std::vector<Material> v_;
  std::string path_;
};

Status bad(const std::string& path, const std::string& why) {
  return Status::Corruption(path + ": " + why);  // bad data, not bad usage
}

}  // namespace

Status read_grid_header(const std::string& path, GridSpec* spec, uint64_t* data_offset) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status::NotFound(path + ": cannot open the grid model file");
  std::string line;
  if (!std::getline(in, line) || line != kMagic) {
    return bad(path, "not a weaver grid model (first line must be '" + std::string(kMagic) + "')");
  }
  GridSpec& s = *spec;
  std::string l1, l2, l3;
  std::getline(in, l1);
  std::getline(in, l2);
  std::getline(in, l3);
  std::istringstream dims(l1), origin(l2), step(l3);
  std::string extra;
  if (!(dims >> s.nx >> s.ny >> s.nz) || (dims >> extra))
    return bad(path, "line 2 must be 'NX NY NZ'");
  if (!(origin >> s.x0 >> s.y0 >> s.z0)) return bad(path, "line 3 must be 'X0 Y0 Z0'");
  if (!(step >> s.dx >> s.dy >> s.dz)) return bad(path, "line 4 must be 'DX DY DZ'");
  if (s.nx < 2 || s.ny < 2 || s.nz < 2 || s.nx > 100000 || s.ny > 100000 || s.nz > 100000) {
    return bad(path, "grid dimensions must be in [2, 100000]");
  }
  if (!(s.dx > 0 && s.dy > 0 && s.dz > 0)) return bad(path, "grid spacing must be positive");
  const size_t count = size_t(s.nx) * s.ny * s.nz;
  const std::streampos data_start = in.tellg();
  in.seekg(0, std::ios::end);
  const size_t bytes = static_cast<size_t>(in.tellg() - data_start);
  if (bytes != count * 12) {
    return bad(path, "expected " + std::to_string(count * 12) +
                         " bytes of float32 data after "
                         "the header, found " +
                         std::to_string(bytes));
  }
  *data_offset = static_cast<uint64_t>(data_start);
  return Status::Ok();
}

Status load_grid_model(const std::string& path, std::unique_ptr<VelocityModel>* out) {
  GridSpec s;
  uint64_t data_start = 0;
  WEAVER_RETURN_IF_ERROR(read_grid_header(path, &s, &data_start));
  std::ifstream in(path, std::ios::binary);
  const size_t count = size_t(s.nx) * s.ny * s.nz;
  in.seekg(static_cast<std::streamoff>(data_start));
  std::vector<Material> values(count);
  std::vector<float> raw(count * 3);
  in.read(reinterpret_cast<char*>(raw.data()), static_cast<std::streamsize>(raw.size() * 4));
  if (!in) return bad(path, "cannot read the grid data");
  for (size_t i = 0; i < count; ++i) {
    values[i] = {raw[3 * i], raw[3 * i + 1], raw[3 * i + 2]};
    const Material& m = values[i];
    if (!(m.vp > 0 && m.vs > 0 && m.rho > 0) || !std::isfinite(m.vp) || !std::isfinite(m.vs) ||
        !std::isfinite(m.rho)) {
      return bad(path, "grid point " + std::to_string(i) +
                           " has a non-positive or non-finite Vp, Vs or density");
    }
  }
  *out = std::make_unique<GridModel>(s, std::move(values), path);
  return Status::Ok();
}

Status write_grid_model(const std::string& path, const GridSpec& s,
                        const std::vector<Material>& values) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << kMagic << "\n"
      << s.nx << " " << s.ny << " " << s.nz << "\n"
      << s.x0 << " " << s.y0 << " " << s.z0 << "\n"
      << s.dx << " " << s.dy << " " << s.dz << "\n";
  for (const Material& m : values) {
    const float f[3] = {m.vp, m.vs, m.rho};
    out.write(reinterpret_cast<const char*>(f), sizeof f);
  }
  return out ? Status::Ok() : Status::IOError("cannot write " + path);
}

}  // namespace weaver
