#include "model/geo_frame.h"

#include <cmath>
#include <complex>
#include <cstdio>
#include <sstream>
#include <vector>

namespace weaver {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180;
// WGS84.
constexpr double kA = 6378137.0;
constexpr double kF = 1 / 298.257223563;

// The series' constants (Karney 2011, section 4): n the third flattening,
// A the rectifying radius, alpha for the forward map, beta for the inverse.
struct Series {
  double e, A, alpha[7], beta[7];
  Series() {
    e = std::sqrt(kF * (2 - kF));
    const double n = kF / (2 - kF), n2 = n * n, n3 = n2 * n, n4 = n3 * n, n5 = n4 * n, n6 = n5 * n;
    A = kA / (1 + n) * (1 + n2 / 4 + n4 / 64 + n6 / 256);
    alpha[1] =
        n / 2 - 2 * n2 / 3 + 5 * n3 / 16 + 41 * n4 / 180 - 127 * n5 / 288 + 7891 * n6 / 37800;
    alpha[2] =
        13 * n2 / 48 - 3 * n3 / 5 + 557 * n4 / 1440 + 281 * n5 / 630 - 1983433 * n6 / 1935360;
    alpha[3] = 61 * n3 / 240 - 103 * n4 / 140 + 15061 * n5 / 26880 + 167603 * n6 / 181440;
    alpha[4] = 49561 * n4 / 161280 - 179 * n5 / 168 + 6601661 * n6 / 7257600;
    alpha[5] = 34729 * n5 / 80640 - 3418889 * n6 / 1995840;
    alpha[6] = 212378941 * n6 / 319334400;
    beta[1] = n / 2 - 2 * n2 / 3 + 37 * n3 / 96 - n4 / 360 - 81 * n5 / 512 + 96199 * n6 / 604800;
    beta[2] = n2 / 48 + n3 / 15 - 437 * n4 / 1440 + 46 * n5 / 105 - 1118711 * n6 / 3870720;
    beta[3] = 17 * n3 / 480 - 37 * n4 / 840 - 209 * n5 / 4480 + 5569 * n6 / 90720;
    beta[4] = 4397 * n4 / 161280 - 11 * n5 / 504 - 830251 * n6 / 7257600;
    beta[5] = 4583 * n5 / 161280 - 108847 * n6 / 3991680;
    beta[6] = 20648693 * n6 / 638668800;
  }
};

const Series& series() {
  static const Series s;
  return s;
}

// tan of the conformal latitude from tan of the geodetic one.
// sqrt(a^2 + b^2) for the modest values here (|tan| < 12 below 85
// degrees): glibc's careful hypot was a sixth of an export's time.
double norm2(double a, double b) { return std::sqrt(a * a + b * b); }

double conformal_tan(double tau, double e) {
  const double sigma = std::sinh(e * std::atanh(e * tau / norm2(1.0, tau)));
  return tau * norm2(1.0, sigma) - sigma * norm2(1.0, tau);
}

// The inverse of conformal_tan, by Newton's method (Karney 2011, eq. 19-21).
double geodetic_tan(double tau_c, double e) {
  const double e2m = 1 - e * e;
  double tau = tau_c;
  for (int i = 0; i < 8; ++i) {
    const double tc = conformal_tan(tau, e);
    const double d =
        (tau_c - tc) / norm2(1.0, tc) * (1 + e2m * tau * tau) / (e2m * norm2(1.0, tau));
    tau += d;
    if (std::abs(d) < 1e-15 * std::max(1.0, std::abs(tau))) break;
  }
  return tau;
}

// sum_j c[j] sin(2 j zeta), j = 1..6, for complex zeta = xi + i eta, by
// Clenshaw's recurrence: one complex sine and cosine instead of twelve
// real sines and hyperbolic functions.  Its real part is
// sum c[j] sin(2j xi) cosh(2j eta), its imaginary part sum c[j] cos(2j xi)
// sinh(2j eta): the series of Karney's eqs. 11 and 7.
std::complex<double> sine_series(const double c[7], std::complex<double> zeta) {
  const double s = std::sin(2 * zeta.real()), co = std::cos(2 * zeta.real());
  const double ex = std::exp(2 * zeta.imag()), sh = (ex - 1 / ex) / 2, ch = (ex + 1 / ex) / 2;
  const std::complex<double> sin2{s * ch, co * sh}, two_cos{2 * co * ch, -2 * s * sh};
  std::complex<double> b1 = 0, b2 = 0;
  for (int j = 6; j >= 1; --j) {
    const std::complex<double> b = c[j] + two_cos * b1 - b2;
    b2 = b1, b1 = b;
  }
  return b1 * sin2;
}

// The Gauss-Krüger (xi, eta) of a point, on the unit rectifying sphere.
void forward_xi_eta(double lat, double dlon, double* xi, double* eta) {
  const Series& s = series();
  const double tc = conformal_tan(std::tan(lat), s.e);
  const double xp = std::atan2(tc, std::cos(dlon));
  const double ep = std::asinh(std::sin(dlon) / norm2(tc, std::cos(dlon)));
  const std::complex<double> d = sine_series(s.alpha, {xp, ep});
  *xi = xp + d.real(), *eta = ep + d.imag();
}

double normalized(double degrees) {
  double d = std::fmod(degrees + 180, 360);
  if (d < 0) d += 360;
  return d - 180;
}

// The origin latitude's xi (the meridian arc on the unit sphere).
double origin_xi(double lat_o) {
  double xi0, eta0;
  forward_xi_eta(lat_o * kDeg, 0, &xi0, &eta0);
  return xi0;
}

void tm_forward(const TransverseMercator& tm, double xi0, double lon, double lat, double* e,
                double* n) {
  const Series& s = series();
  double xi, eta;
  forward_xi_eta(lat * kDeg, normalized(lon - tm.lon_c) * kDeg, &xi, &eta);
  *e = tm.false_e + tm.k0 * s.A * eta;
  *n = tm.false_n + tm.k0 * s.A * (xi - xi0);
}

void tm_inverse(const TransverseMercator& tm, double xi0, double e, double n, double* lon,
                double* lat) {
  const Series& s = series();
  const double xi = (n - tm.false_n) / (tm.k0 * s.A) + xi0, eta = (e - tm.false_e) / (tm.k0 * s.A);
  const std::complex<double> d = sine_series(s.beta, {xi, eta});
  const double xp = xi - d.real(), ep = eta - d.imag();
  const double tc = std::sin(xp) / norm2(std::sinh(ep), std::cos(xp));
  *lat = std::atan(geodetic_tan(tc, s.e)) / kDeg;
  *lon = normalized(tm.lon_c + std::atan2(std::sinh(ep), std::cos(xp)) / kDeg);
}

TransverseMercator projection_of(const GeoFrame& g) {
  TransverseMercator tm;
  if (g.utm_zone == 0) {
    tm.lon_c = g.lon0, tm.lat_o = g.lat0;
  } else {
    tm.lon_c = 6.0 * g.utm_zone - 183, tm.k0 = 0.9996, tm.false_e = 500000;
    tm.false_n = g.utm_south ? 10000000 : 0;
  }
  return tm;
}

}  // namespace

void TransverseMercator::forward(double lon, double lat, double* e, double* n) const {
  tm_forward(*this, origin_xi(lat_o), lon, lat, e, n);
}

void TransverseMercator::inverse(double e, double n, double* lon, double* lat) const {
  tm_inverse(*this, origin_xi(lat_o), e, n, lon, lat);
}

GeoTransform::GeoTransform(const GeoFrame& g)
    : tm_(projection_of(g)),
      xi0_(origin_xi(tm_.lat_o)),
      sin_(std::sin(g.azimuth * kDeg)),
      cos_(std::cos(g.azimuth * kDeg)) {
  tm_forward(tm_, xi0_, g.lon0, g.lat0, &e0_, &n0_);
}

void GeoTransform::to_frame(double lon, double lat, double* x, double* y) const {
  double e, n;
  tm_forward(tm_, xi0_, lon, lat, &e, &n);
  const double de = e - e0_, dn = n - n0_;
  *x = de * sin_ + dn * cos_;
  *y = de * cos_ - dn * sin_;
}

void GeoTransform::to_geo(double x, double y, double* lon, double* lat) const {
  tm_inverse(tm_, xi0_, e0_ + x * sin_ + y * cos_, n0_ + x * cos_ - y * sin_, lon, lat);
}

void GeoFrame::to_frame(double lon, double lat, double* x, double* y) const {
  GeoTransform(*this).to_frame(lon, lat, x, y);
}

void GeoFrame::to_geo(double x, double y, double* lon, double* lat) const {
  GeoTransform(*this).to_geo(x, y, lon, lat);
}

std::string GeoFrame::to_text() const {
  char buf[128];
  std::snprintf(buf, sizeof buf, "%.10g,%.10g,%.10g", lon0, lat0, azimuth);
  std::string t = buf;
  if (utm_zone != 0) t += ",utm" + std::to_string(utm_zone) + (utm_south ? "s" : "");
  return t;
}

Status GeoFrame::parse(const std::string& text, GeoFrame* out) {
  GeoFrame g;
  std::vector<std::string> parts;
  std::stringstream in(text);
  for (std::string p; std::getline(in, p, ',');) parts.push_back(p);
  auto number = [&](size_t i, double* v) {
    size_t used = 0;
    try {
      *v = std::stod(parts[i], &used);
    } catch (const std::exception&) {
      used = 0;
    }
    return used == parts[i].size() && std::isfinite(*v);
  };
  const bool utm = !parts.empty() && parts.back().rfind("utm", 0) == 0;
  const size_t numbers = parts.size() - (utm ? 1 : 0);
  if (numbers < 2 || numbers > 3 || !number(0, &g.lon0) || !number(1, &g.lat0) ||
      (numbers == 3 && !number(2, &g.azimuth))) {
    return Status::InvalidArgument("a geographic origin is LON,LAT[,AZIMUTH][,utmZONE[s]], not '" +
                                   text + "'");
  }
  if (!(g.lon0 >= -180 && g.lon0 <= 180 && g.lat0 > -85 && g.lat0 < 85)) {
    return Status::InvalidArgument(
        "the origin must have longitude in [-180, 180] and latitude "
        "in (-85, 85), not '" +
        text + "'");
  }
  if (utm) {
    std::string z = parts.back().substr(3);
    g.utm_south = !z.empty() && (z.back() == 's' || z.back() == 'S');
    if (g.utm_south) z.pop_back();
    int zone = 0;
    if (z.empty() || z.size() > 2 || z.find_first_not_of("0123456789") != std::string::npos ||
        (zone = std::stoi(z)) < 1 || zone > 60) {
      return Status::InvalidArgument("a UTM zone is 1..60 (with 's' for the south), not '" +
                                     parts.back().substr(3) + "'");
    }
    g.utm_zone = zone;
  }
  *out = g;
  return Status::Ok();
}

}  // namespace weaver
