// `weaver export`: the mesh out of the database into the files of the tools
// of the field, streamed in id order (memory bounded by the budget, never by
// the mesh), each file written beside its final name and renamed into place
// when complete.
//
//   csv        nodes.csv and elements.csv of DESIGN.md (coordinates in ticks)
//   pvtu       the vtu cut into --parts pieces, and the index ParaView opens
//   vtu        VTK XML UnstructuredGrid, raw binary appended data, 64-bit
//              headers and ids; VTK_HEXAHEDRON cells in VTK's corner order;
//              cell data element_id, level, edge, vp, vs, rho (qp, qs); point data
//              node_id, kind (0 anchored, 1 edge, 2 face)      (export_vtu.cc)
//   msh        Gmsh MSH 4.1 ASCII, hexahedra (type 5) in Gmsh's corner order,
//              element data level (and vp, vs, rho; qp, qs)    (export_msh.cc)
//   metis      the element dual graph in METIS's graph format (gpmetis): an
//              edge for every pair of elements sharing a face, the finer
//              faces across a 2:1 step included              (export_metis.cc)
//   metis-mesh the elements as mpmetis's mesh file             (export_metis.cc)
//   raw        a directory: mesh.bin, little-endian arrays, and mesh.json
//              naming each array's dtype, shape and offset     (export_raw.cc)
#pragma once

#include <cstdint>
#include <string>

#include "schema/status.h"
#include "util/memory_budget.h"
#include "util/progress.h"

namespace weaver {

enum class ExportFormat { kCsv, kVtu, kPvtu, kMsh, kMetis, kMetisMesh, kRaw };
// "csv", "vtu", ...; false for an unknown name.
bool export_format_from_name(const std::string& name, ExportFormat* out);

enum class ExportUnits { kTicks, kMetres };

struct ExportOptions {
  ExportFormat format = ExportFormat::kCsv;
  // csv: either of these (empty: skip), or out as a directory for both.
  std::string nodes_path, elements_path;
  std::string out;
  // Coordinates of vtu, msh and raw (csv is always in ticks), and of the box.
  ExportUnits units = ExportUnits::kMetres;
  // z written as elevation, up (metres: the top's elevation minus the
  // depth), so that viewers show mountains upright; hexahedra keep a
  // positive orientation (their corners taken top face first).
  bool z_up = false;
  // vtu, pvtu, msh, raw: only the elements that share a point with the box
  // x0,y0,z0,x1,y1,z1 (in the units), with just the nodes they use (and, for
  // raw, the anchors of those that dangle), numbered compactly in global id
  // order; node_id and element_id keep the global ids.
  bool has_box = false;
  double box[6] = {0, 0, 0, 0, 0, 0};
  // vtu with a box: more elements than this in the box (0: no limit) is
  // refused before anything is written, ExportResult::elements saying how
  // many (weaver serve's cap, counted on the state the export reads).
  uint64_t max_elements = 0;
  // pvtu: pieces of consecutive element ids, equal in count.
  uint32_t parts = 1;
  MemoryBudget memory;
  // Items written (nodes, then elements) and their fraction of all of them.
  ProgressFn progress;
};

// Where export's memory goes: the shares of options.memory.
struct ExportMemory {
  explicit ExportMemory(MemoryBudget budget);

  MemoryPlan plan;
  uint64_t node_pool = 0;    // the node table: corners and anchors are found in it by key
  uint64_t octant_pool = 0;  // the octant table, read in order (and searched, for metis)
  uint64_t buffers = 0;      // the output's section buffers, all together
  uint64_t scratch = 0;      // a selection's node set: its sort and its tree
};

struct ExportResult {
  uint64_t nodes = 0, elements = 0;
  uint64_t graph_edges = 0;  // metis: element pairs sharing a face
  uint64_t bytes = 0;        // written, all files
};

Status export_mesh(const std::string& db_dir, const ExportOptions& options, ExportResult* result);

// STEM of OUT = STEM.pvtu: the directory where pvtu's pieces go.
std::string pvtu_stem(const std::string& out);

// raw and pvtu with --parts N written a part at a time by separate writers
// (weaver-mpi export: one a rank), into the same files export_mesh writes:
// export_parts_begin once (raw: makes OUT.tmp; pvtu: the pieces' directory),
// then export_one_part for each part, in any process and order, then
// export_parts_end once, told whether every part was written (raw: writes
// parts.json and renames OUT.tmp to OUT, or removes OUT.tmp; pvtu: writes the
// index last, or leaves it unwritten).  A part's shared nodes are found from
// its own elements and their neighbours (SharedNodes::build_part).
Status export_parts_begin(const ExportOptions& options);
Status export_one_part(const std::string& db_dir, const ExportOptions& options, uint32_t part,
                       ExportResult* result);
Status export_parts_end(const std::string& db_dir, const ExportOptions& options, bool written,
                        ExportResult* result);

}  // namespace weaver
