#include "balance/balance.h"

#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <memory>

#include "balance/balance_progress.h"
#include "balance/closure.h"
#include "balance/refinement.h"
#include "db/database.h"
#include "model/velocity_model.h"
#include "modeldb/open_model.h"
#include "schema/octant.h"

namespace weaver {
namespace {

// The model named in the table's metadata, if it is a built-in one or a
// model database ("db:MODEL.db", read within `memory` by `threads` threads).
std::unique_ptr<VelocityModel> model_of(const std::string& metadata, MemoryBudget memory,
                                        int threads) {
  const size_t at = metadata.find("model=");
  if (at == std::string::npos) return nullptr;
  const std::string name = metadata.substr(at + 6, metadata.find(';', at) - at - 6);
  std::unique_ptr<VelocityModel> m;
  if (name == "grid" || !open_velocity_model(name, "", memory, threads, &m).ok()) return nullptr;
  return m;
}

// New leaves of a table built from a model get the model's vp, vs and rho
// (and qp, qs where the table has them) at their centre, where the table's
// schema has those fields; other tables (and other fields) keep the
// parent's values.
FillPayload material_fill(const VelocityModel* model, const TableOptions& table) {
  const Field* vp = table.schema.find("vp");
  const Field* vs = table.schema.find("vs");
  const Field* rho = table.schema.find("rho");
  if (model == nullptr || vp == nullptr || vs == nullptr || rho == nullptr) return nullptr;
  Units u;
  units_from_metadata(table.metadata, &u);
  const double tick_m = u.tick_m;
  const Field* qp = table.schema.find("qp");
  const Field* qs = table.schema.find("qs");
  return [model, tick_m, vp, vs, rho, qp, qs](const Octant& o, std::byte* payload) {
    const double h = octant_edge(o) * tick_m / 2;
    const Material m = model->at(o.x * tick_m + h, o.y * tick_m + h, o.z * tick_m + h);
    RecordSchema::set_double(payload, *vp, m.vp);
    RecordSchema::set_double(payload, *vs, m.vs);
    RecordSchema::set_double(payload, *rho, m.rho);
    if (qp != nullptr) RecordSchema::set_double(payload, *qp, m.qp);
    if (qs != nullptr) RecordSchema::set_double(payload, *qs, m.qs);
  };
}

}  // namespace

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
  spool_buffer = std::min<uint64_t>(plan.take("spools (84 buffers)", 1, 8) / 84, 1ull << 20);
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
  model = plan.take_budget("model readers", 1, 32);
}

int finest_level_bound(BTree& leaves) {
  LevelCounts levels{};
  return levels_from_metadata(leaves.options().metadata, &levels) ? finest_level(levels)
                                                                  : kMaxLevel;
}

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
  TableOptions topt = leaves->options();
  if (o.output_packed >= 0) topt.packed = o.output_packed == 1;
  std::unique_ptr<BTree> out;
  std::string file;
  WEAVER_RETURN_IF_ERROR(db->create_table(kOctantTable, topt, memory.output_pool, &out, &file));
  const std::unique_ptr<VelocityModel> model =
      model_of(topt.metadata, memory.model, std::max(1, o.threads));
  const Status st = write_refinement(*leaves, closure.required(), material_fill(model.get(), topt),
                                     *out, o.threads, progress.get(), r, o.keep_from, o.keep_to);
  if (st.ok()) out->set_metadata(with_levels(topt.metadata, r->levels));
  return db->publish(kOctantTable, file, out, st);
}

}  // namespace weaver
