#include "modeldb/db_model.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "db/database.h"
#include "schema/octant.h"
#include "storage/btree.h"

namespace weaver {

struct DbModel::Reader {
  std::unique_ptr<BTree> table;
  Status opened;
  // The last octant found: [lo, lo + edge) ticks, and its values.
  Coord lo{0, 0, 0};
  uint32_t edge = 0;
  ModelHit last;
};

DbModel::~DbModel() = default;

Status DbModel::open(const std::string& dir, MemoryBudget memory, std::unique_ptr<DbModel>* out) {
  std::unique_ptr<DbModel> m(new DbModel());
  m->dir_ = dir;
  WEAVER_RETURN_IF_ERROR(Database::open(dir, Database::Mode::kRead, false, &m->db_));
  if (!m->db_->has_table(kModelTable)) {
    return Status::NotFound(dir + ": no model table (make one with 'weaver model import')");
  }
  m->pool_bytes_ = std::max<uint64_t>(memory.bytes() / 4, 1ull << 20);
  std::unique_ptr<BTree> t;
  WEAVER_RETURN_IF_ERROR(m->db_->open_table(kModelTable, m->pool_bytes_, &t));
  model_info_from_metadata(t->options().metadata, &m->info_);
  m->octants_ = t->size();
  for (int a = 0; a < 3; ++a) {
    const double ticks = std::floor(m->info_.extent_m[a] / m->info_.tick_m + 1e-6);
    m->limit_[a] = static_cast<uint32_t>(std::clamp(ticks - 1, 0.0, double(kRootEdge - 1)));
  }
  *out = std::move(m);
  return Status::Ok();
}

DbModel::Reader& DbModel::reader() const {
  std::lock_guard<std::mutex> lock(mu_);
  auto& r = readers_[std::this_thread::get_id()];
  if (!r) {
    r = std::make_unique<Reader>();
    r->opened = db_->open_table(kModelTable, pool_bytes_, &r->table);
  }
  return *r;
}

Status DbModel::find(Reader& r, double x, double y, double z, ModelHit* hit) const {
  WEAVER_RETURN_IF_ERROR(r.opened);
  const double m[3] = {x, y, z};
  uint32_t t[3];
  bool clamped = false;
  for (int a = 0; a < 3; ++a) {
    const double ticks = std::floor((m[a] - info_.origin_m[a]) / info_.tick_m);
    const double c = std::clamp(ticks, 0.0, double(limit_[a]));
    clamped = clamped || c != ticks;
    t[a] = static_cast<uint32_t>(c);
  }
  if (t[0] - r.lo.x < r.edge && t[1] - r.lo.y < r.edge && t[2] - r.lo.z < r.edge) {
    *hit = r.last;
    hit->clamped = clamped;
    return Status::Ok();
  }
  uint64_t key = 0;
  bool found = false;
  std::byte payload[sizeof(ModelValues)] = {};
  WEAVER_RETURN_IF_ERROR(r.table->floor(pixel_key({t[0], t[1], t[2]}), &key, payload, &found));
  const Octant o = found ? octant_from_key(key) : Octant{};
  if (!found || !octant_contains_point(o, {t[0], t[1], t[2]})) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "the model has no octant at (%g, %g, %g) m", x, y, z);
    return Status::NotFound(buf);
  }
  std::memcpy(r.last.values.data(), payload, r.table->options().schema.record_size());
  r.last.octant = o;
  r.lo = octant_corner(o);
  r.edge = octant_edge(o);
  *hit = r.last;
  hit->clamped = clamped;
  return Status::Ok();
}

Status DbModel::lookup(double x, double y, double z, ModelHit* hit) const {
  return find(reader(), x, y, z, hit);
}

Material DbModel::at(double x, double y, double z) const {
  ModelHit h;
  // A hole in the model: the point takes no material (construct refuses
  // nothing here; the octant's Vs of 0 asks for the finest leaves).
  if (!lookup(x, y, z, &h).ok()) return {};
  return {h.values[0], h.values[1], h.values[2]};
}

void DbModel::vs_on_lattice(const double* xs, const double* ys, const double* zs, int n,
                            float* out) const {
  Reader& r = reader();
  ModelHit h;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        out[(k * n + j) * n + i] = find(r, xs[i], ys[j], zs[k], &h).ok() ? h.values[1] : 0.0f;
      }
}

std::string DbModel::describe() const {
  return "model database " + dir_ + " (" + info_.source + ", " + std::to_string(octants_) +
         " octants)";
}

}  // namespace weaver
