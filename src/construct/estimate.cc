#include "construct/estimate.h"

#include <sys/statvfs.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "util/printable.h"

namespace weaver {
namespace {

// Sampling cells per domain: enough to see a basin's bowls, cheap (one model
// sample each, a few milliseconds).
constexpr double kSampleCells = 32768;
// Bytes per leaf of an octant table with materials, packed: from 0.9 where
// neighbours share their materials (measured: the 2 Hz basin 1.06, the 1 Hz
// test rfile 0.95) to 6 where every leaf has its own (the 2 Hz basin under
// a DEM, its materials read by depth below the ground: 5.2); plain: 20.2.
constexpr double kPackedLeafBytesLeast = 0.9, kPackedLeafBytes = 6, kPlainLeafBytes = 21;
// `mesh` adds the node table (about 0.7 bytes a leaf: the 2 Hz basin's is
// 0.69) and the boundary table (a few hundredths), and its scratch keeps
// the peak within 5% of the final database (measured by ground_bench.py).
constexpr double kMeshBytesPerLeaf = 0.8, kScratch = 1.05;
// Room kept free for everything else on the disk.
constexpr double kHeadroom = 1.1;

}  // namespace

double free_disk_bytes(const std::string& dir) {
  std::filesystem::path p = std::filesystem::absolute(dir);
  std::error_code ec;
  while (!p.empty() && !std::filesystem::exists(p, ec) && p != p.parent_path()) p = p.parent_path();
  struct statvfs s;
  if (::statvfs(p.c_str(), &s) != 0) return -1;
  return double(s.f_bavail) * double(s.f_frsize);
}

ConstructEstimate planned_estimate(const ConstructPlan& p) {
  ConstructEstimate e;
  e.elements = p.estimated_elements;
  e.disk_bytes = p.estimated_disk_bytes;
  e.least_disk_bytes = p.estimated_least_disk_bytes;
  return e;
}

void ZOrderShare::add(uint64_t cell_key, double leaves) { cells_.push_back({cell_key, leaves}); }

void ZOrderShare::finish() {
  std::sort(cells_.begin(), cells_.end());
  total_ = 0;
  for (auto& [key, leaves] : cells_) leaves = total_ += leaves;  // now: up to and with the cell
}

double ZOrderShare::fraction_before(uint64_t key) const {
  auto it = std::lower_bound(cells_.begin(), cells_.end(), std::make_pair(key, 0.0));
  if (it == cells_.begin() || total_ <= 0) return 0;
  return (it - 1)->second / total_;
}

ConstructEstimate estimate_construct(const ConstructOptions& o, const ConstructPlan& p,
                                     const VelocityModel& model, ZOrderShare* share) {
  ConstructEstimate e;
  const double blocks = double(p.blocks[0]) * p.blocks[1] * p.blocks[2];
  int level = p.block_level;
  while (level < o.max_level && blocks * std::pow(8.0, level + 1 - p.block_level) <= kSampleCells) {
    ++level;
  }
  e.sample_level = level;
  const uint64_t n = uint64_t{1} << (level - p.block_level);  // cells per block side
  const uint64_t cells[3] = {p.blocks[0] * n, p.blocks[1] * n, p.blocks[2] * n};
  // Very many blocks (a domain rounded up to level-10 blocks): every
  // step-th cell per axis, each standing for step^3 cells.
  const double total = double(cells[0]) * cells[1] * cells[2];
  const uint64_t step = std::max<uint64_t>(1, uint64_t(std::ceil(std::cbrt(total / kSampleCells))));
  const double weight =
      total / (double((cells[0] + step - 1) / step) * double((cells[1] + step - 1) / step) *
               double((cells[2] + step - 1) / step));
  const double cell_m = p.root_edge_m / std::ldexp(1.0, level), rate = o.freq * o.ppw;
  for (uint64_t k = 0; k < cells[2]; k += step)
    for (uint64_t j = 0; j < cells[1]; j += step)
      for (uint64_t i = 0; i < cells[0]; i += step) {
        // Vs at the cell centre: the least Vs over a cell as coarse as this
        // one would ask for leaves much finer than the material around.
        const double vs = std::max<double>(
            model.at((i + 0.5) * cell_m, (j + 0.5) * cell_m, (k + 0.5) * cell_m).vs, o.vs_min);
        // The leaf level the rule asks for here: edge <= vs / rate.
        double want = std::ceil(std::log2(p.root_edge_m * rate / std::max(vs, 1e-300)));
        want = std::clamp(want, double(std::max(o.min_level, p.block_level)), double(o.max_level));
        const double leaves = weight * std::pow(8.0, want - level);
        e.elements += leaves;
        if (share != nullptr) {
          const uint32_t edge = octant_edge(level);
          share->add(octant_key({uint32_t(i * edge), uint32_t(j * edge), uint32_t(k * edge),
                                 uint8_t(level)}),
                     leaves);
        }
      }
  if (share != nullptr) share->finish();
  const double mesh = o.whole_pipeline ? kMeshBytesPerLeaf : 0;
  e.table_bytes = e.elements * (o.packed ? kPackedLeafBytes : kPlainLeafBytes);
  e.disk_bytes = (e.table_bytes + e.elements * mesh) * kScratch * kHeadroom;
  e.least_disk_bytes =
      e.elements * ((o.packed ? kPackedLeafBytesLeast : kPlainLeafBytes) + mesh) * kScratch;
  return e;
}

Status check_construct_fits(const ConstructOptions& o, const ConstructEstimate& e,
                            const std::string& db_dir) {
  if (e.elements > double(o.max_elements)) {
    return Status::InvalidArgument("the octree would have about " + si_text(e.elements) +
                                   " elements, more than --max-elements " +
                                   si_text(double(o.max_elements)) +
                                   " (lower --freq or --domain, or raise --max-elements)");
  }
  const double avail = free_disk_bytes(db_dir);
  if (avail >= 0 && e.least_disk_bytes > avail) {
    return Status::InvalidArgument("the octree would have about " + si_text(e.elements) +
                                   " elements needing at least " + si_text(e.least_disk_bytes) +
                                   "B of disk, but " + db_dir + " has " + si_text(avail) +
                                   "B free");
  }
  return Status::Ok();
}

}  // namespace weaver
