#include "balance/balance.h"

#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <memory>

#include "balance/balance_progress.h"
#include "balance/closure.h"
#include "balance/refinement.h"
#include "balance/window_balance.h"
#include "db/database.h"
#include "model/ground_model.h"
#include "model/velocity_model.h"
#include "modeldb/model_identity.h"
#include "modeldb/open_model.h"
#include "schema/octant.h"

namespace weaver {
namespace {

// The model named in the table's metadata: a built-in one, an older
// build's "db:PATH", or a model database's identity, looked for in
// model_dirs (read within `memory` by `threads` threads).  Null where a
// name does not open (a grid file's table keeps its parents' values).
Status model_of(const std::string& metadata, const std::vector<std::string>& model_dirs,
                MemoryBudget memory, int threads, std::unique_ptr<VelocityModel>* out) {
  out->reset();
  const size_t at = metadata.find("model=");
  if (at == std::string::npos) return Status::Ok();
  std::string name = metadata.substr(at + 6, metadata.find(';', at) - at - 6);
  if (is_model_identity(name)) {
    const std::string dir = find_model_database(name, model_dirs);
    if (dir.empty()) {
      return Status::NotFound("the octants were built from model " + name +
                              ", which is not this database's model table: name its model "
                              "database with --model db:PATH");
    }
    name = "db:" + dir;
  }
  if (name == "grid" || !open_velocity_model(name, "", memory, threads, out).ok()) out->reset();
  return Status::Ok();
}

// New leaves of a table built under a ground (its metadata names the
// surface): its solid fraction, and none where it lies wholly above the
// ground, as construct carves; the material (where a model opens) through
// the ground, as construct samples it.
struct Carving {
  std::unique_ptr<Surface> surface;
  Ground ground;
  const Field* solid = nullptr;
};

FillPayload fill_from(const VelocityModel* model, const TableOptions& table,
                      std::shared_ptr<const Carving> carving) {
  const Field* vp = table.schema.find("vp");
  const Field* vs = table.schema.find("vs");
  const Field* rho = table.schema.find("rho");
  const bool material = model != nullptr && vp != nullptr && vs != nullptr && rho != nullptr;
  if (!material && carving == nullptr) return nullptr;
  Units u;
  units_from_metadata(table.metadata, &u);
  const double tick_m = u.tick_m;
  const Field* qp = table.schema.find("qp");
  const Field* qs = table.schema.find("qs");
  return
      [model, material, carving, tick_m, vp, vs, rho, qp, qs](const Octant& o, std::byte* payload) {
        const double e = octant_edge(o) * tick_m, h = e / 2;
        if (carving != nullptr) {
          const double lo[3] = {o.x * tick_m, o.y * tick_m, o.z * tick_m};
          const double hi[3] = {lo[0] + e, lo[1] + e, lo[2] + e};
          const double f = solid_fraction(carving->ground, lo, hi);
          if (f <= 0) return false;
          RecordSchema::set_double(payload, *carving->solid, static_cast<float>(f));
        }
        if (!material) return true;
        const Material m = model->at(o.x * tick_m + h, o.y * tick_m + h, o.z * tick_m + h);
        RecordSchema::set_double(payload, *vp, m.vp);
        RecordSchema::set_double(payload, *vs, m.vs);
        RecordSchema::set_double(payload, *rho, m.rho);
        if (qp != nullptr) RecordSchema::set_double(payload, *qp, m.qp);
        if (qs != nullptr) RecordSchema::set_double(payload, *qs, m.qs);
        return true;
      };
}

}  // namespace

Status model_material_fill(const TableOptions& table, const std::vector<std::string>& model_dirs,
                           MemoryBudget memory, MemoryBudget surface, int threads,
                           std::unique_ptr<VelocityModel>* model, FillPayload* fill) {
  WEAVER_RETURN_IF_ERROR(model_of(table.metadata, model_dirs, memory, std::max(1, threads), model));
  auto carving = std::make_shared<Carving>();
  carving->solid = table.schema.find("solid");
  const Status ground =
      ground_of_metadata(table.metadata, surface.bytes(), &carving->surface, &carving->ground);
  if (!ground.ok() && ground.code() != Status::Code::kNotFound) return ground;
  if (!ground.ok() || carving->solid == nullptr) {
    carving.reset();
  } else if (*model != nullptr) {
    // The model as construct asked it: through the ground (the surface
    // stays the carving's, which the fill holds).
    *model = std::make_unique<GroundedModel>(std::move(*model), carving->ground);
  }
  *fill = fill_from(model->get(), table, carving);
  return Status::Ok();
}

BalanceMemory::BalanceMemory(MemoryBudget budget) : plan(budget) {
  // The closure reads the leaves in order with one cursor per level, and
  // the refinement with one more: a modest pool keeps their pages cached.
  leaf_pool = plan.take("leaf table pool", 1, 8, 32ull << 20);
  // A sorted append touches only the right spine of the output.
  output_pool = plan.take("output table pool", 1, 8, 8ull << 20);
  // 4 spools a level for levels 0..kMaxLevel (84 of them: the leaves'
  // parents from each of the first scan's two stretches, the required
  // octants' parents, the required), each buffering sorted runs on their
  // way to its file.
  const uint64_t spools = plan.take("spools (84 buffers)", 1, 8);
  spool_buffer = std::min<uint64_t>(spools / 84, 1ull << 20);
  // The larger the chunk of parents, the more neighbours it finds among
  // itself and never hands to the sorter.
  parent_chunk = plan.take("parent chunk", 1, 4);
  candidate_sort = plan.take("candidate sorter", 1, 4);
  // A finer map leaves fewer candidates to the table (those in cells the
  // domain's boundary cuts) and takes 8 times the memory: 32 MiB is level 9.
  domain_map = plan.take("domain map", 1, 16, 32ull << 20);
  // It reads its stretch of the leaves in order: a few pages at a time.
  second_reader = plan.take("second reader's pool", 1, 64, 1ull << 20);
  // A model database's readers, for the material of new leaves.
  model = plan.take_budget("model readers", 1, 64);
  // A carved mesh's surface, for the solid fraction of new leaves.
  surface = plan.take_budget("surface", 1, 64);
  // Windows run instead of the closure, never beside it: they take its
  // chunk, sorter, spools and map.
  windows = parent_chunk + candidate_sort + spools + domain_map;
}

int finest_level_bound(BTree& leaves) {
  LevelCounts levels{};
  return levels_from_metadata(leaves.options().metadata, &levels) ? finest_level(levels)
                                                                  : kMaxLevel;
}

namespace {

// The windows' way (window_balance.h): false in *fitted if a leaf alone
// outgrew the memory, and then nothing is written.
Status balance_by_windows(Database& db, BTree& leaves, const BalanceOptions& o,
                          const BalanceMemory& memory, const TableOptions& topt,
                          const FillPayload& fill, bool one_window, BalanceResult* r,
                          bool* fitted) {
  if (one_window && !one_window_may_fit(leaves, memory.windows)) {
    *fitted = false;  // told before a table is made for it
    return Status::Ok();
  }
  std::vector<std::unique_ptr<BTree>> more;
  WindowOptions wo;
  WEAVER_RETURN_IF_ERROR(window_options(db, leaves, o, memory, &more, &wo));
  wo.progress = o.progress;
  wo.one_window = one_window;
  std::unique_ptr<BTree> out;
  std::string file;
  WEAVER_RETURN_IF_ERROR(db.create_table(kOctantTable, topt, memory.output_pool, &out, &file));
  Status st = balance_in_windows(wo, fill, *out, r, fitted);
  if (st.ok() && !*fitted) {
    db.publish(kOctantTable, file, out, Status::Internal("a window outgrew the memory"));
    *r = BalanceResult{};
    return Status::Ok();
  }
  if (st.ok()) out->set_metadata(with_levels(topt.metadata, r->levels));
  return db.publish(kOctantTable, file, out, st);
}

}  // namespace

Status balance_octree(const std::string& db_dir, const BalanceOptions& o, BalanceResult* r) {
  *r = BalanceResult{};
  const BalanceMemory memory(o.memory);
  std::unique_ptr<Database> db;
  WEAVER_RETURN_IF_ERROR(Database::open(
      db_dir, o.check_only ? Database::Mode::kRead : Database::Mode::kWrite, false, &db));
  std::unique_ptr<BTree> leaves;
  WEAVER_RETURN_IF_ERROR(db->open_table(kOctantTable, memory.leaf_pool, &leaves));
  // A reader keeps its scratch out of the database directory, where a
  // writer's open would remove it as a leftover.
  if (o.check_only) {
    return check_balance(*leaves, o, std::filesystem::temp_directory_path().string(), r);
  }
  TableOptions topt = leaves->options();
  if (o.output_packed >= 0) topt.packed = o.output_packed == 1;
  std::unique_ptr<VelocityModel> model;
  FillPayload fill;
  std::vector<std::string> model_dirs = o.model_dirs;
  model_dirs.push_back(db_dir);
  WEAVER_RETURN_IF_ERROR(model_material_fill(topt, model_dirs, memory.model, memory.surface,
                                             o.threads, &model, &fill));
  const bool windows = o.algorithm != BalanceOptions::Algorithm::kClosure;
  if (windows && o.keep_from == 0 && o.keep_to == UINT64_MAX) {
    // Auto: one window of all the leaves where the memory holds it (it
    // reads no layers), else windows on every thread; windows asked for:
    // they first, then one window (so too for the tests' short windows).
    // On any number of threads: one thread's windows are sized for output
    // four times their input, so even one thread's can be many where one
    // window holds the table.
    const bool auto_way = o.algorithm == BalanceOptions::Algorithm::kAuto && o.window_leaves == 0;
    for (bool one_window : {auto_way, !auto_way}) {
      bool fitted = false;
      WEAVER_RETURN_IF_ERROR(
          balance_by_windows(*db, *leaves, o, memory, topt, fill, one_window, r, &fitted));
      if (fitted) return Status::Ok();
    }
  }
  ScratchDir scratch{db_dir + "/tmp-balance-" + std::to_string(::getpid())};
  std::unique_ptr<BalanceProgress> progress;
  if (o.progress) {
    LevelCounts levels{};
    levels_from_metadata(leaves->options().metadata, &levels);
    progress = std::make_unique<BalanceProgress>(o.progress, leaves->size(), levels);
  }
  std::unique_ptr<BTree> second_reader;
  if (o.threads > 1) {
    WEAVER_RETURN_IF_ERROR(db->open_table(kOctantTable, memory.second_reader, &second_reader));
  }
  Closure closure(*leaves, memory, scratch.path, o, progress.get(), r, second_reader.get());
  WEAVER_RETURN_IF_ERROR(closure.build(finest_level_bound(*leaves), true));
  std::unique_ptr<BTree> out;
  std::string file;
  WEAVER_RETURN_IF_ERROR(db->create_table(kOctantTable, topt, memory.output_pool, &out, &file));
  const Status st = write_refinement(*leaves, closure.required(), fill, *out, o.threads,
                                     progress.get(), r, o.keep_from, o.keep_to);
  if (st.ok()) out->set_metadata(with_levels(topt.metadata, r->levels));
  return db->publish(kOctantTable, file, out, st);
}

}  // namespace weaver
