#include "modeldb/model_import.h"

#include <fcntl.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <functional>
#include <vector>

#include "db/database.h"
#include "model/etree_file.h"
#include "model/grid_model.h"
#include "model/material_merge.h"
#include "schema/octant.h"

namespace weaver {
namespace {

// Octants of one block of a grid, a side: blocks of 32^3 points read in
// 32 x 32 rows keep a block's reads near 400 KB.
constexpr int kGridBlockLevels = 5;

using Emit = std::function<Status(const Octant&, const ModelValues&)>;

// The first field out of range (velocities and density positive, Q not
// negative, all finite), or -1.  Cheap: it runs on every record.
int bad_field(const ModelValues& v, int fields) {
  for (int f = 0; f < fields; ++f) {
    if (!std::isfinite(v[f]) || (f < 3 ? v[f] <= 0 : v[f] < 0)) return f;
  }
  return -1;
}

// The error for a record whose field f is out of range; `what` names it.
Status bad_value(const std::string& what, const ModelValues& v, int f) {
  static const char* names[] = {"Vp", "Vs", "density", "Qp", "Qs"};
  return Status::Corruption(what + " has " + names[f] + " " + std::to_string(v[f]) +
                            " (velocities and density must be positive and finite)");
}

// ---- etree -----------------------------------------------------------------

Status import_etree(EtreeFile* f, const ModelImportOptions& o, ModelInfo* info, uint64_t* read,
                    const Emit& emit) {
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
    if (const int bad = bad_field(v, n); bad >= 0) return bad_value(what(), v, bad);
    ++*read;
    WEAVER_RETURN_IF_ERROR(emit(oct, v));
  }
  return Status::Ok();
}

// ---- grid ------------------------------------------------------------------

struct GridPlan {
  GridSpec s;
  uint64_t data = 0;
  double edge_m = 0;
  std::array<uint32_t, 3> cells{};  // octants a side, one per grid point
  int level = 0;                    // of the octants
};

class GridBlockReader {
 public:
  GridBlockReader(const GridPlan& g, int fd, std::string path)
      : g_(g), fd_(fd), path_(std::move(path)) {}

  // The material of every octant of block [lo, hi) (in cells), into
  // out[((k - lo.z) * side + (j - lo.y)) * side + (i - lo.x)].
  Status read(const std::array<uint32_t, 3>& lo, const std::array<uint32_t, 3>& hi, uint32_t side,
              std::vector<ModelValues>* out) {
    const int n[3] = {g_.s.nx, g_.s.ny, g_.s.nz};
    const double d[3] = {g_.s.dx, g_.s.dy, g_.s.dz};
    for (int a = 0; a < 3; ++a) {
      cell_index_[a].clear();
      cell_frac_[a].clear();
      for (uint32_t c = lo[a]; c < hi[a]; ++c) {
        const double t = std::clamp(c * g_.edge_m / d[a], 0.0, double(n[a] - 1));
        const int i = std::min(static_cast<int>(t), n[a] - 2);
        cell_index_[a].push_back(i);
        cell_frac_[a].push_back(t - i);
      }
      first_[a] = cell_index_[a].front();
      span_[a] = cell_index_[a].back() + 2 - first_[a];
    }
    WEAVER_RETURN_IF_ERROR(read_rows());
    out->assign(size_t{side} * side * side, ModelValues{});
    for (uint32_t k = 0; k < hi[2] - lo[2]; ++k)
      for (uint32_t j = 0; j < hi[1] - lo[1]; ++j)
        for (uint32_t i = 0; i < hi[0] - lo[0]; ++i)
          (*out)[(size_t{k} * side + j) * side + i] = interpolate(i, j, k);
    return Status::Ok();
  }

 private:
  Status read_rows() {
    rows_.resize(size_t(span_[0]) * span_[1] * span_[2] * 3);
    for (int z = 0; z < span_[2]; ++z) {
      for (int y = 0; y < span_[1]; ++y) {
        const uint64_t point =
            (uint64_t(first_[2] + z) * g_.s.ny + (first_[1] + y)) * g_.s.nx + first_[0];
        float* row = &rows_[(size_t(z) * span_[1] + y) * span_[0] * 3];
        const size_t bytes = size_t(span_[0]) * 12;
        if (::pread(fd_, row, bytes, static_cast<off_t>(g_.data + point * 12)) !=
            static_cast<ssize_t>(bytes)) {
          return Status::IOError(path_ + ": cannot read the grid data");
        }
        for (int x = 0; x < span_[0]; ++x) {
          const ModelValues v{row[3 * x], row[3 * x + 1], row[3 * x + 2], 0, 0};
          if (const int bad = bad_field(v, 3); bad >= 0) {
            return bad_value(path_ + ": grid point " + std::to_string(point + x), v, bad);
          }
        }
      }
    }
    return Status::Ok();
  }

  ModelValues interpolate(uint32_t i, uint32_t j, uint32_t k) const {
    const int base[3] = {cell_index_[0][i] - first_[0], cell_index_[1][j] - first_[1],
                         cell_index_[2][k] - first_[2]};
    const double f[3] = {cell_frac_[0][i], cell_frac_[1][j], cell_frac_[2][k]};
    double sum[3] = {0, 0, 0};
    for (int c = 0; c < 8; ++c) {
      const double w =
          ((c & 1) ? f[0] : 1 - f[0]) * ((c & 2) ? f[1] : 1 - f[1]) * ((c & 4) ? f[2] : 1 - f[2]);
      if (w == 0) continue;
      const size_t at =
          ((size_t(base[2] + ((c >> 2) & 1)) * span_[1] + base[1] + ((c >> 1) & 1)) * span_[0] +
           base[0] + (c & 1)) *
          3;
      for (int v = 0; v < 3; ++v) sum[v] += w * rows_[at + v];
    }
    return {float(sum[0]), float(sum[1]), float(sum[2]), 0, 0};
  }

  const GridPlan& g_;
  int fd_;
  std::string path_;
  std::vector<int> cell_index_[3];
  std::vector<double> cell_frac_[3];
  int first_[3] = {0, 0, 0}, span_[3] = {0, 0, 0};
  std::vector<float> rows_;
};

Status plan_grid(const std::string& path, GridPlan* g, ModelInfo* info) {
  WEAVER_RETURN_IF_ERROR(read_grid_header(path, &g->s, &g->data));
  const GridSpec& s = g->s;
  g->edge_m = std::min({s.dx, s.dy, s.dz});
  const int n[3] = {s.nx, s.ny, s.nz};
  const double d[3] = {s.dx, s.dy, s.dz};
  uint32_t most = 1;
  for (int a = 0; a < 3; ++a) {
    g->cells[a] = static_cast<uint32_t>(std::floor((n[a] - 1) * d[a] / g->edge_m + 1e-9)) + 1;
    most = std::max(most, g->cells[a]);
  }
  while ((uint32_t{1} << g->level) < most) ++g->level;
  if (g->level > kMaxLevel) {
    return Status::InvalidArgument(path +
                                   ": the grid needs more than weaver's 2^20 octants a side");
  }
  info->tick_m = g->edge_m * (uint64_t{1} << g->level) / kRootEdge;
  // Octant i is centred on grid point i (on the smallest spacing's axis).
  info->origin_m = {s.x0 - g->edge_m / 2, s.y0 - g->edge_m / 2, s.z0 - g->edge_m / 2};
  for (int a = 0; a < 3; ++a) info->extent_m[a] = g->cells[a] * g->edge_m;
  return Status::Ok();
}

Status import_grid(const GridPlan& g, const std::string& path, uint64_t* read, const Emit& emit) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return Status::NotFound(path + ": cannot open the grid model file");
  GridBlockReader reader(g, fd, path);
  const int block_level = std::max(0, g.level - kGridBlockLevels);
  const uint32_t side = uint32_t{1} << (g.level - block_level);  // cells a block
  const uint32_t cell_ticks = octant_edge(g.level);
  std::vector<ModelValues> values;
  // Blocks in Z-order, those that meet the grid's box.
  std::function<Status(const Octant&)> visit = [&](const Octant& b) -> Status {
    const uint32_t shift = kMaxLevel - g.level;
    const std::array<uint32_t, 3> lo = {b.x >> shift, b.y >> shift, b.z >> shift};
    if (lo[0] >= g.cells[0] || lo[1] >= g.cells[1] || lo[2] >= g.cells[2]) return Status::Ok();
    if (b.level < block_level) {
      for (int c = 0; c < 8; ++c) WEAVER_RETURN_IF_ERROR(visit(octant_child(b, c)));
      return Status::Ok();
    }
    std::array<uint32_t, 3> hi;
    for (int a = 0; a < 3; ++a) hi[a] = std::min(lo[a] + side, g.cells[a]);
    WEAVER_RETURN_IF_ERROR(reader.read(lo, hi, side, &values));
    for (uint64_t m = 0; m < uint64_t{side} * side * side; ++m) {
      const Coord c = morton_decode(m);
      if (lo[0] + c.x >= hi[0] || lo[1] + c.y >= hi[1] || lo[2] + c.z >= hi[2]) continue;
      const Octant o{b.x + c.x * cell_ticks, b.y + c.y * cell_ticks, b.z + c.z * cell_ticks,
                     static_cast<uint8_t>(g.level)};
      ++*read;
      WEAVER_RETURN_IF_ERROR(emit(o, values[(size_t(c.z) * side + c.y) * side + c.x]));
    }
    return Status::Ok();
  };
  const Status st = visit(octant_root());
  ::close(fd);
  return st;
}

}  // namespace

Status import_model(const std::string& db_dir, const ModelImportOptions& o, ModelImportResult* r) {
  *r = ModelImportResult{};
  const size_t colon = o.from.find(':');
  const std::string kind = o.from.substr(0, colon == std::string::npos ? 0 : colon);
  const std::string path = colon == std::string::npos ? "" : o.from.substr(colon + 1);
  if ((kind != "etree" && kind != "grid") || path.empty()) {
    return Status::InvalidArgument("--from must be etree:FILE or grid:FILE, not '" + o.from + "'");
  }
  if (!(o.tolerance >= 0) || !std::isfinite(o.tolerance)) {
    return Status::InvalidArgument("--tolerance must be a number >= 0");
  }
  // The source's headers first: a bad file is refused before anything is
  // written.  An etree says whether it holds Q; a grid never does.
  ModelInfo& info = r->info;
  info.source = kind + " " + path;
  std::unique_ptr<EtreeFile> etree;
  GridPlan grid;
  if (kind == "etree") {
    WEAVER_RETURN_IF_ERROR(EtreeFile::open(path, &etree));
  } else {
    WEAVER_RETURN_IF_ERROR(plan_grid(path, &grid, &info));
  }
  const bool has_q = etree && etree->field("Qp") && etree->field("Qs");
  std::unique_ptr<Database> db;
  WEAVER_RETURN_IF_ERROR(Database::open(db_dir, Database::Mode::kWrite, true, &db));
  MemoryPlan plan(o.memory);
  const uint64_t pool = plan.take("model table pool", 1, 8, 8ull << 20);
  TableOptions topt;
  topt.key_kind = KeyKind::kOctant;
  topt.schema = model_schema(has_q);
  topt.packed = o.packed;
  std::unique_ptr<BTree> table;
  std::string file;
  WEAVER_RETURN_IF_ERROR(db->create_table(kModelTable, topt, pool, &table, &file));
  // The record is ModelValues' leading floats (the schema packs f32 little-endian).
  static_assert(sizeof(ModelValues) == kModelFields * sizeof(float));
  MaterialMerger merger(o.tolerance, has_q ? 5 : 3, [&](uint64_t key, const ModelValues& v) {
    ++r->levels[octant_key_level(key)];
    return table->append(key, reinterpret_cast<const std::byte*>(v.data()));
  });
  const Emit emit = [&](const Octant& oct, const ModelValues& v) { return merger.add(oct, v); };
  Status st = etree ? import_etree(etree.get(), o, &info, &r->read, emit)
                    : import_grid(grid, path, &r->read, emit);
  if (st.ok()) st = merger.finish();
  r->octants = merger.emitted();
  if (st.ok() && r->octants == 0) st = Status::Corruption(path + ": the model has no leaves");
  if (st.ok()) table->set_metadata(model_info_to_metadata(info) + levels_to_metadata(r->levels));
  WEAVER_RETURN_IF_ERROR(db->publish(kModelTable, file, table, st));
  r->table_bytes = table->file_bytes();
  return Status::Ok();
}

}  // namespace weaver
