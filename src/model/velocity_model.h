// Seismic velocity models: P and S wave speeds and density at a point.
// Coordinates are metres from the domain origin: x and y horizontal, z depth
// (positive down).
#pragma once

#include <algorithm>
#include <array>
#include <memory>
#include <string>

#include "schema/record_schema.h"
#include "schema/status.h"

namespace weaver {

struct Material {
  float vp = 0, vs = 0, rho = 0;  // m/s, m/s, kg/m^3
  float qp = 0, qs = 0;           // quality factors, where the model has them (has_q())
};

// The payload of a table of materials (the octant table of a mesh built
// from a model, a model database's table): f32 fields, Qp and Qs last and
// only where the model has them.
inline RecordSchema material_schema(bool has_q) {
  std::string error;
  return *RecordSchema::parse(
      has_q ? "vp:f32,vs:f32,rho:f32,qp:f32,qs:f32" : "vp:f32,vs:f32,rho:f32", &error);
}

class VelocityModel {
 public:
  virtual ~VelocityModel() = default;
  virtual Material at(double x, double y, double z) const = 0;
  // at(x, y, z).vs, to the bit; models override it where Vs alone is cheaper.
  virtual float vs_at(double x, double y, double z) const { return at(x, y, z).vs; }
  // Vs, rounded as at() rounds it, at every point (xs[i], ys[j], zs[k]) of
  // an n x n x n lattice, into out[(k * n + j) * n + i]: what construct asks
  // of every octant it splits (n = 5: the 3 x 3 x 3 sample points of all
  // eight children).  Models override it when the points can share work.
  virtual void vs_on_lattice(const double* xs, const double* ys, const double* zs, int n,
                             float* out) const {
    for (int k = 0; k < n; ++k)
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) out[(k * n + j) * n + i] = vs_at(xs[i], ys[j], zs[k]);
  }
  // at() at every point (xs[i], ys[j], zs[k]) of an n x n x n lattice, into
  // out[(k * n + j) * n + i], the same to the bit: construct asks it for the
  // centres of eight sibling leaves (n = 2), into storage it has not
  // initialised: each out[] is assigned whole.  Models override it when the
  // points can share work.
  virtual void materials_on_lattice(const double* xs, const double* ys, const double* zs, int n,
                                    Material* out) const {
    for (int k = 0; k < n; ++k)
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) out[(k * n + j) * n + i] = at(xs[i], ys[j], zs[k]);
  }
  // The same for n x n columns whose points each have their own depth:
  // column (i, j) at (xs[i], ys[j]), its n points at depths
  // zs[(j * n + i) * n + k], into out[(k * n + j) * n + i].  A model under a
  // ground (model/ground_model.h) asks so, each column shifted by the
  // ground over it; models override it where a column shares work.
  virtual void vs_on_columns(const double* xs, const double* ys, const double* zs, int n,
                             float* out) const {
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i)
        for (int k = 0; k < n; ++k)
          out[(k * n + j) * n + i] = vs_at(xs[i], ys[j], zs[(j * n + i) * n + k]);
  }
  virtual void materials_on_columns(const double* xs, const double* ys, const double* zs, int n,
                                    Material* out) const {
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i)
        for (int k = 0; k < n; ++k)
          out[(k * n + j) * n + i] = at(xs[i], ys[j], zs[(j * n + i) * n + k]);
  }
  // Bounds on the Vs at() gives at every point of the closed box [lo, hi]
  // (metres), rounded as at() rounds it: *vs_lo <= at(p).vs <= *vs_hi.
  // Construct decides an octant from them where they settle it and samples
  // it only where they do not.  A bound too wide costs samples; one too
  // narrow would change the mesh.  False: the model cannot say cheaply.
  virtual bool vs_bounds(const double lo[3], const double hi[3], float* vs_lo, float* vs_hi) const {
    (void)lo, (void)hi, (void)vs_lo, (void)vs_hi;
    return false;
  }
  // vs_bounds of each box c with want[c] among the eight that halve a box
  // on every axis: box c spans [edges[a][b], edges[a][b + 1]] on axis a,
  // b its bit a; ok[c] is vs_bounds' answer.  The same answers as eight
  // calls (construct asks it for an octant's children); models override it
  // where the boxes share work.
  virtual void vs_bounds_of_eighths(const double edges[3][3], const bool want[8], float vs_lo[8],
                                    float vs_hi[8], bool ok[8]) const {
    for (int c = 0; c < 8; ++c) {
      if (!want[c]) continue;
      double lo[3], hi[3];
      for (int a = 0; a < 3; ++a) {
        const int b = (c >> a) & 1;
        lo[a] = edges[a][b], hi[a] = edges[a][b + 1];
      }
      ok[c] = vs_bounds(lo, hi, &vs_lo[c], &vs_hi[c]);
    }
  }
  // The points asked next (until the next focus, on this thread) lie in the
  // box [lo, hi] (metres, bounds included): construct says so before each
  // subtree.  A model read from storage loads the box once, and says false
  // where its memory could not hold it (each point is then searched for in
  // storage; a read error says true: the points report it); others ignore it.
  virtual bool focus(const double lo[3], const double hi[3]) const {
    (void)lo;
    (void)hi;
    return true;
  }
  // Whether focus() loads the box (a model read from storage): construct
  // then keeps its subtrees at their level, since a larger box costs that
  // model more to load and search than the fewer leaves around it save.
  virtual bool loads_focus() const { return false; }
  // Whether at() gives Qp and Qs (else they are 0): a mesh built from such a
  // model carries them to its leaves and exports.
  virtual bool has_q() const { return false; }
  // "" when the model has values over the whole box [0, domain_m] (metres);
  // else which sides of it reach past the model's own box, whose edge values
  // at() gives there (construct says so, or refuses with --outside error).
  virtual std::string outside(const std::array<double, 3>& domain_m) const {
    (void)domain_m;
    return "";
  }
  // Where the model's frame lies on the Earth (model/geo_frame.h's text
  // form), "" when the model does not say.
  virtual std::string geo() const { return ""; }
  // The model's own PROJ string (an rfile's), kept as text and never
  // interpreted; "" when it has none.
  virtual std::string projection() const { return ""; }
  // A one-line description with the parameters, for logs and metadata.
  virtual std::string describe() const = 0;
};

// A lattice's depths zs (n of them) as vs_on_columns takes them: each of
// its n x n columns the same, columns[(j * n + i) * n + k] = zs[k].
inline void lattice_as_columns(const double* zs, int n, double* columns) {
  for (int c = 0; c < n * n; ++c)
    for (int k = 0; k < n; ++k) columns[c * n + k] = zs[k];
}

// "halfspace", "loh1", "basin", or "grid" (with grid_file).  InvalidArgument
// for an unknown name; grid file errors name the file.
Status make_model(const std::string& name, const std::string& grid_file,
                  std::unique_ptr<VelocityModel>* out);

}  // namespace weaver
