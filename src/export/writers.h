// What the writers of export.h share: the job (mesh, path, units, progress)
// and one function per format.  Internal to src/export.
#pragma once

#include <array>
#include <functional>
#include <string>

#include "export/export.h"
#include "export/output_file.h"
#include "mesh/mesh_reader.h"

namespace weaver {

// VTK_HEXAHEDRON and Gmsh's hexahedron number the corners counter-clockwise
// around the bottom face, then the top one; weaver's corner k has x fastest.
// Point i of a VTK or Gmsh hexahedron is weaver's corner kVtkHexCorner[i].
inline constexpr std::array<int, 8> kVtkHexCorner = {0, 1, 3, 2, 4, 5, 7, 6};

struct ExportJob {
  Mesh& mesh;
  const ExportOptions& options;
  size_t section_buffer;  // bytes for each section of an output file
  ExportResult* result;
  uint64_t done = 0, total = 1;

  // Before the passes: how many items (nodes and elements) they write.
  void plan(uint64_t items) { total = std::max<uint64_t>(items, 1); }
  // One item written; reports now and then.
  void tick() {
    if (options.progress && ++done % (1 << 16) == 0) options.progress(done, double(done) / total);
  }
  // A coordinate in ticks, in the job's units.
  double coord(int axis, uint32_t ticks) const {
    if (options.units == ExportUnits::kTicks) return ticks;
    return mesh.units().origin_m[axis] + mesh.units().tick_m * ticks;
  }
  double length(uint32_t ticks) const {
    return options.units == ExportUnits::kTicks ? ticks : mesh.units().tick_m * ticks;
  }
  const char* unit_name() const { return options.units == ExportUnits::kTicks ? "ticks" : "m"; }
};

// Ends a text file written as one section: flushes, counts its bytes, and
// renames it into place.
Status finish_text(ExportJob& job, Section& out, OutputFile& file);
// A text file of `head` and then one line per element (line_of appends the
// line's text, without the newline); corner ids are looked up if with_nodes.
Status write_element_lines(ExportJob& job, const std::string& path, const std::string& head,
                           bool with_nodes,
                           const std::function<void(const MeshElement&, LineBuffer&)>& line_of);

Status write_csv(ExportJob& job);
Status write_vtu(ExportJob& job);
Status write_msh(ExportJob& job);
Status write_metis_graph(ExportJob& job);
Status write_metis_mesh(ExportJob& job);
Status write_raw(ExportJob& job);

}  // namespace weaver
