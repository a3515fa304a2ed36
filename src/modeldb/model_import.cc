#include "modeldb/model_import.h"

#include <fcntl.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <functional>
#include <vector>

#include "db/database.h"
#include "model/etree_file.h"
#include "model/material_merge.h"
#include "modeldb/grid_import.h"
#include "modeldb/import_source.h"
#include "modeldb/rfile_import.h"
#include "schema/octant.h"

namespace weaver {
namespace {

// ---- etree -----------------------------------------------------------------

Status import_etree(EtreeFile* f, const ModelImportOptions& o, ModelInfo* info, uint64_t* read,
                    const ModelEmit& emit) {
  const std::string& path = f->path();
  const EtreeField* fields[5] = {f->field("Vp"), f->field("Vs"), f->field("density"),
                                 f->field("Qp"), f->field("Qs")};
  if (!fields[2]) fields[2] = f->field("rho");
  if (!fields[0] || !fields[1] || !fields[2]) {
    std::string has;
    for (const EtreeField& fl : f->info().fields) has += (has.empty() ? "" : ", ") + fl.name;
    return Status::Corruption(path + ": its schema has no Vp, Vs and density (it has " + has + ")");
  }
  info->has_q = fields[3] && fields[4];
  const int n = info->has_q ? 5 : 3;
  double root_m = o.root_edge_m;
  Status placed = etree_placement(f->info().app_metadata, &root_m, info);
  if (o.root_edge_m > 0) {
    root_m = o.root_edge_m;
  } else if (!placed.ok()) {
    return Status::InvalidArgument(path + ": " + placed.message());
  }
  info->tick_m = root_m / kRootEdge;
  for (double& e : info->extent_m) e = e > 0 ? e : root_m;
  if (info->producer.empty()) info->producer = f->info().app_metadata.substr(0, 200);
  WEAVER_RETURN_IF_ERROR(f->start());
  constexpr int kShift = kEtreeMaxLevel - kMaxLevel;  // 2^31 ticks -> 2^20
  for (;;) {
    EtreeOctant e;
    bool done = false;
    WEAVER_RETURN_IF_ERROR(f->next(&e, &done));
    if (done) break;
    if (!e.leaf) continue;  // interior octants (the USGS file's means)
    const Octant oct{e.x >> kShift, e.y >> kShift, e.z >> kShift, static_cast<uint8_t>(e.level)};
    auto what = [&] {
      return path + ": octant (" + std::to_string(e.x) + " " + std::to_string(e.y) + " " +
             std::to_string(e.z) + " level " + std::to_string(e.level) + ")";
    };
    if (e.level > kMaxLevel)
      return Status::Corruption(what() + " is finer than weaver's 20 levels");
    ModelValues v{};
    for (int i = 0; i < n; ++i) v[i] = static_cast<float>(f->read_field(e.payload, *fields[i]));
    if (const int bad = bad_model_field(v, n); bad >= 0) return bad_model_value(what(), v, bad);
    ++*read;
    WEAVER_RETURN_IF_ERROR(emit(oct, v));
  }
  return Status::Ok();
}

// A source's headers, read (and checked) before anything is written.
struct SourcePlan {
  std::string kind, path;
  std::unique_ptr<EtreeFile> etree;
  GridPlan grid;
  LayerPlan layers;
  XyzGrid xyz;
  RfilePlan rfile;
  bool has_q = false;
};

Status plan_source(const ModelImportOptions& o, SourcePlan* s, ModelInfo* info) {
  const size_t colon = o.from.find(':');
  s->kind = o.from.substr(0, colon == std::string::npos ? 0 : colon);
  s->path = colon == std::string::npos ? "" : o.from.substr(colon + 1);
  const std::string& k = s->kind;
  if ((k != "etree" && k != "grid" && k != "layers" && k != "xyz" && k != "rfile") ||
      s->path.empty()) {
    return Status::InvalidArgument(
        "--from must be etree:FILE, grid:FILE, layers:FILE, xyz:FILE or rfile:FILE, not '" +
        o.from + "'");
  }
  info->source = k + " " + s->path;
  if (k == "etree") {
    WEAVER_RETURN_IF_ERROR(EtreeFile::open(s->path, &s->etree));
    s->has_q = s->etree->field("Qp") && s->etree->field("Qs");
  } else if (k == "grid") {
    WEAVER_RETURN_IF_ERROR(plan_grid(s->path, &s->grid, info));
  } else if (k == "rfile") {
    // Its column cache: a quarter of the budget, beside the table pool.
    WEAVER_RETURN_IF_ERROR(
        plan_rfile(s->path, MemoryBudget(o.memory.bytes() / 4), o.threads, &s->rfile, info));
    s->has_q = info->has_q;
  } else if (k == "layers") {
    WEAVER_RETURN_IF_ERROR(plan_layers(s->path, &s->layers, info));
    s->has_q = s->layers.table.has_q;
  } else {
    WEAVER_RETURN_IF_ERROR(scan_xyz_grid(s->path, &s->xyz));
  }
  return Status::Ok();
}

// The octants of the source, in key order.  An xyz file goes through a grid
// file in the database's directory, removed after.
Status emit_source(SourcePlan& s, const ModelImportOptions& o, MemoryBudget blocks,
                   const std::string& db_dir, ModelInfo* info, uint64_t* read,
                   MaterialMerger& merger) {
  const ModelEmit emit = [&](const Octant& oct, const ModelValues& v) {
    return merger.add(oct, v);
  };
  if (s.kind == "etree") return import_etree(s.etree.get(), o, info, read, emit);
  if (s.kind == "layers") return import_layers(s.layers, read, emit);
  if (s.kind == "rfile") {
    // The subtrees in flight (two a thread), each held by a worker, share
    // the grid's blocks' budget (twice their bytes: room for growth).
    RfileImportRun run;
    run.threads = std::max(1, o.threads);
    run.tolerance = o.tolerance;
    run.fields = s.has_q ? 5 : 3;
    const uint64_t per_cell = sizeof(MaterialMerger::Entry);
    run.task_cells =
        o.rfile_task_cells > 0
            ? o.rfile_task_cells
            : std::clamp<uint64_t>(blocks.bytes() / (4 * run.threads * per_cell), 4096, 1 << 16);
    return import_rfile(s.rfile, *info, run, read, &merger);
  }
  if (s.kind == "grid") return import_grid(s.grid, s.path, blocks, read, merger);
  const std::string grid = db_dir + "/xyz-import.grid.tmp";
  WEAVER_RETURN_IF_ERROR(write_xyz_as_grid(s.path, s.xyz, grid));
  const std::string source = info->source;
  Status st = plan_grid(grid, &s.grid, info);
  if (st.ok()) st = import_grid(s.grid, grid, blocks, read, merger);
  info->source = source;
  ::unlink(grid.c_str());
  return st;
}

}  // namespace

constexpr size_t kAppendBatch = 4096;

Status import_model(const std::string& db_dir, const ModelImportOptions& o, ModelImportResult* r) {
  *r = ModelImportResult{};
  if (!(o.tolerance >= 0) || !std::isfinite(o.tolerance)) {
    return Status::InvalidArgument("--tolerance must be a number >= 0");
  }
  ModelInfo& info = r->info;
  SourcePlan source;
  WEAVER_RETURN_IF_ERROR(plan_source(o, &source, &info));
  const bool has_q = source.has_q;
  std::unique_ptr<Database> db;
  WEAVER_RETURN_IF_ERROR(Database::open(db_dir, Database::Mode::kWrite, true, &db));
  MemoryPlan plan(o.memory);
  const uint64_t pool = plan.take("model table pool", 1, 8, 8ull << 20);
  // A grid's block of points, read and merged in memory (grid_import.h).
  const MemoryBudget blocks = plan.take_budget("grid blocks", 1, 2);
  TableOptions topt;
  topt.key_kind = KeyKind::kOctant;
  topt.schema = material_schema(has_q);
  topt.packed = o.packed;
  std::unique_ptr<BTree> table;
  std::string file;
  WEAVER_RETURN_IF_ERROR(db->create_table(kModelTable, topt, pool, &table, &file));
  // The record is ModelValues' leading floats (the schema packs f32 little-endian).
  static_assert(sizeof(ModelValues) == kModelFields * sizeof(float));
  // Appended a batch at a time (a record at a time was a tenth of a grid import).
  const size_t record = topt.schema.record_size();
  std::vector<uint64_t> keys;
  std::vector<std::byte> records;
  uint64_t stored = 0;
  auto flush = [&]() {
    const Status s = table->append_batch(keys.data(), records.data(), keys.size());
    stored += keys.size();
    if (o.progress) o.progress(stored, -1);
    keys.clear();
    records.clear();
    return s;
  };
  MaterialMerger merger(o.tolerance, has_q ? 5 : 3, [&](uint64_t key, const ModelValues& v) {
    ++r->levels[octant_key_level(key)];
    keys.push_back(key);
    const std::byte* bytes = reinterpret_cast<const std::byte*>(v.data());
    records.insert(records.end(), bytes, bytes + record);
    return keys.size() < kAppendBatch ? Status::Ok() : flush();
  });
  Status st = emit_source(source, o, blocks, db_dir, &info, &r->read, merger);
  if (st.ok()) st = merger.finish();
  if (st.ok()) st = flush();
  r->octants = merger.emitted();
  if (st.ok() && r->octants == 0) {
    st = Status::Corruption(source.path + ": the model has no leaves");
  }
  if (st.ok()) table->set_metadata(model_info_to_metadata(info) + levels_to_metadata(r->levels));
  WEAVER_RETURN_IF_ERROR(db->publish(kModelTable, file, table, st));
  r->table_bytes = table->file_bytes();
  return Status::Ok();
}

}  // namespace weaver
