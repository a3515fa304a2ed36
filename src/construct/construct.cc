#include "construct/construct.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <vector>

#include "construct/estimate.h"
#include "db/database.h"
#include "model/velocity_model.h"
#include "schema/octant.h"

namespace weaver {
namespace {

// The deepest block level tried when fitting the domain: 2^10 blocks a side.
constexpr int kMaxBlockLevel = 10;
// Leaves written per append_batch call.
constexpr size_t kBatch = 4096;
constexpr char kMaterialSchema[] = "vp:f32,vs:f32,rho:f32";

class Descent {
 public:
  Descent(const ConstructOptions& o, const ConstructPlan& p, const VelocityModel& m, BTree& out,
          ConstructResult* r)
      : o_(o), p_(p), model_(m), out_(out), r_(r), inv_rate_(1.0 / (o.freq * o.ppw)) {
    if (o_.progress) estimate_construct(o_, p_, model_, &share_);
  }

  Status run() {
    const uint32_t e = octant_edge(p_.block_level);
    for (uint32_t k = 0; k < p_.blocks[2]; ++k)
      for (uint32_t j = 0; j < p_.blocks[1]; ++j)
        for (uint32_t i = 0; i < p_.blocks[0]; ++i) {
          blocks_.push_back(octant_key({i * e, j * e, k * e, uint8_t(p_.block_level)}));
        }
    std::sort(blocks_.begin(), blocks_.end());  // Z-order
    for (uint64_t key : blocks_) WEAVER_RETURN_IF_ERROR(visit(octant_from_key(key)));
    return flush();
  }

 private:
  // The least Vs over the 27 sample points, floored by --vs-min.
  double vs_min_of(const Octant& o) const {
    const double t = p_.tick_m, h = octant_edge(o) * t / 2;
    return std::max(model_.min_vs_on_lattice(o.x * t, o.y * t, o.z * t, h), o_.vs_min);
  }

  Status visit(const Octant& o) {
    const double edge_m = octant_edge(o) * p_.tick_m;
    const double vs = vs_min_of(o);
    const bool too_big = edge_m > vs * inv_rate_;
    if (o.level < o_.min_level || (too_big && o.level < o_.max_level)) {
      for (int c = 0; c < 8; ++c) WEAVER_RETURN_IF_ERROR(visit(octant_child(o, c)));
      return Status::Ok();
    }
    return emit(o, edge_m, vs);
  }

  Status emit(const Octant& o, double edge_m, double vs) {
    const double t = p_.tick_m, half = edge_m / 2;
    const Material m = model_.at(o.x * t + half, o.y * t + half, o.z * t + half);
    keys_.push_back(octant_key(o));
    const float f[3] = {m.vp, m.vs, m.rho};
    const size_t at = payloads_.size();
    payloads_.resize(at + sizeof f);
    std::memcpy(payloads_.data() + at, f, sizeof f);
    ++r_->levels[o.level];
    const double ppw = vs / (o_.freq * edge_m);
    if (r_->elements == 0 || edge_m < r_->smallest_edge_m) r_->smallest_edge_m = edge_m;
    r_->largest_edge_m = std::max(r_->largest_edge_m, edge_m);
    if (r_->elements == 0 || ppw < r_->worst_ppw) r_->worst_ppw = ppw;
    ++r_->elements;
    if (keys_.size() == kBatch) return flush();
    return Status::Ok();
  }

  Status flush() {
    WEAVER_RETURN_IF_ERROR(out_.append_batch(keys_.data(), payloads_.data(), keys_.size()));
    if (o_.progress && !keys_.empty()) {
      o_.progress(r_->elements, share_.fraction_before(keys_.back()));
    }
    keys_.clear();
    payloads_.clear();
    return Status::Ok();
  }

  const ConstructOptions& o_;
  const ConstructPlan& p_;
  const VelocityModel& model_;
  BTree& out_;
  ConstructResult* r_;
  double inv_rate_;
  std::vector<uint64_t> blocks_, keys_;
  std::vector<std::byte> payloads_;
  ZOrderShare share_;  // for the progress fraction
};

}  // namespace

Status plan_construct(const ConstructOptions& o, ConstructPlan* p) {
  for (double l : o.domain_m) {
    if (!(l > 0) || !std::isfinite(l))
      return Status::InvalidArgument("domain sizes must be positive");
  }
  if (!(o.freq > 0) || !(o.ppw > 0) || o.vs_min < 0) {
    return Status::InvalidArgument("--freq and --ppw must be positive, --vs-min not negative");
  }
  if (o.min_level < 0 || o.max_level > kMaxLevel || o.min_level > o.max_level) {
    return Status::InvalidArgument("levels must satisfy 0 <= min level <= max level <= 20");
  }
  p->root_edge_m = std::max({o.domain_m[0], o.domain_m[1], o.domain_m[2]});
  p->tick_m = p->root_edge_m / kRootEdge;
  // The coarsest block level at which every side is a whole number of blocks.
  p->block_level = kMaxBlockLevel;
  p->rounded_up = true;
  for (int b = 0; b <= kMaxBlockLevel; ++b) {
    const double block = p->root_edge_m / (1 << b);
    bool whole = true;
    for (double l : o.domain_m) whole = whole && std::abs(l / block - std::round(l / block)) < 1e-9;
    if (whole) {
      p->block_level = b;
      p->rounded_up = false;
      break;
    }
  }
  const double block = p->root_edge_m / (1 << p->block_level);
  for (int a = 0; a < 3; ++a) {
    p->blocks[a] = static_cast<uint32_t>(std::ceil(o.domain_m[a] / block - 1e-9));
    p->domain_m[a] = p->blocks[a] * block;
  }
  if (p->block_level > o.max_level) {
    return Status::InvalidArgument("the domain needs blocks of level " +
                                   std::to_string(p->block_level) + ", finer than --max-level");
  }
  std::unique_ptr<VelocityModel> model;
  WEAVER_RETURN_IF_ERROR(make_model(o.model, o.grid_file, &model));
  p->model = model->describe();
  const ConstructEstimate e = estimate_construct(o, *p, *model);
  p->estimated_elements = e.elements;
  p->estimated_disk_bytes = e.disk_bytes;
  return Status::Ok();
}

ConstructMemory::ConstructMemory(MemoryBudget budget) : plan(budget) {
  // A sorted append touches only the right spine of the table.
  table_pool = plan.take("octant table pool", 1, 8, 8ull << 20);
}

Status construct_octree(const std::string& db_dir, const ConstructOptions& o, ConstructPlan* p,
                        ConstructResult* r) {
  *r = ConstructResult{};
  WEAVER_RETURN_IF_ERROR(plan_construct(o, p));
  std::unique_ptr<VelocityModel> model;
  WEAVER_RETURN_IF_ERROR(make_model(o.model, o.grid_file, &model));
  ConstructEstimate e;
  e.elements = p->estimated_elements;
  e.disk_bytes = p->estimated_disk_bytes;
  WEAVER_RETURN_IF_ERROR(check_construct_fits(o, e, db_dir));
  std::unique_ptr<Database> db;
  WEAVER_RETURN_IF_ERROR(Database::open(db_dir, Database::Mode::kWrite, true, &db));
  TableOptions topt;
  topt.key_kind = KeyKind::kOctant;
  std::string error;
  topt.schema = *RecordSchema::parse(kMaterialSchema, &error);
  topt.packed = o.packed;
  std::unique_ptr<BTree> table;
  std::string file;
  WEAVER_RETURN_IF_ERROR(
      db->create_table(kOctantTable, topt, ConstructMemory(o.memory).table_pool, &table, &file));
  Descent descent(o, *p, *model, *table, r);
  Status st = descent.run();
  if (st.ok()) {
    Units u;
    u.tick_m = p->tick_m;
    char model_meta[256];
    std::snprintf(model_meta, sizeof model_meta, ";model=%s;freq=%.17g;ppw=%.17g;vs_min=%.17g",
                  o.model.c_str(), o.freq, o.ppw, o.vs_min);
    table->set_metadata(units_to_metadata(u) + levels_to_metadata(r->levels) + model_meta);
  }
  WEAVER_RETURN_IF_ERROR(db->publish(kOctantTable, file, table, st));
  r->table_bytes = table->file_bytes();
  return Status::Ok();
}

}  // namespace weaver
