// What the writers of export.h share: the job (mesh, path, units, progress)
// and one function per format.  Internal to src/export.
#pragma once

#include <array>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "export/export.h"
#include "export/output_file.h"
#include "export/selection.h"
#include "mesh/mesh_reader.h"
#include "model/geo_frame.h"

namespace weaver {

// VTK_HEXAHEDRON and Gmsh's hexahedron number the corners counter-clockwise
// around the bottom face, then the top one; weaver's corner k has x fastest.
// Point i of a VTK or Gmsh hexahedron is weaver's corner kVtkHexCorner[i].
inline constexpr std::array<int, 8> kVtkHexCorner = {0, 1, 3, 2, 4, 5, 7, 6};
// The same with z mirrored (export --z-up): the deeper face first.
inline constexpr std::array<int, 8> kVtkHexCornerZUp = {4, 5, 7, 6, 0, 1, 3, 2};

struct ExportJob {
  ExportJob(Mesh& m, const ExportOptions& o, size_t buffer, uint64_t scratch, ExportResult* r)
      : mesh(m), options(o), section_buffer(buffer), scratch_bytes(scratch), result(r) {}

  Mesh& mesh;
  const ExportOptions& options;
  size_t section_buffer;   // bytes for each section of an output file
  uint64_t scratch_bytes;  // for building a selection's node set
  ExportResult* result;
  uint64_t done = 0, total = 1;
  // What is written: the whole mesh unless --box or a piece says otherwise.
  // (select() must run before the writer: for the whole mesh it is cheap.)
  Selection sel;
  std::unique_ptr<LocalNodes> local;

  // Builds `local` for s (with the anchors of dangling nodes, for raw).
  Status select(const Selection& s, bool with_anchors, const std::string& scratch_dir) {
    sel = s;
    local = std::make_unique<LocalNodes>();
    return local->build(mesh, sel, with_anchors, scratch_dir, scratch_bytes);
  }
  // The Selection of options.box (in ticks, the far bounds rounded up).
  Status box_selection(Selection* s) const;
  uint64_t node_count() const { return local->node_count(); }
  uint64_t element_count() const { return local->element_count(); }

  // Before the passes: how many items (nodes and elements) they write.
  void plan(uint64_t items) { total = std::max<uint64_t>(items, 1); }
  // One item written; reports now and then.
  void tick() {
    if (options.progress && ++done % (1 << 16) == 0) options.progress(done, double(done) / total);
  }
  // A coordinate in ticks, in the job's units (z as elevation with z_up).
  double coord(int axis, uint32_t ticks) const {
    if (options.units == ExportUnits::kTicks) return ticks;
    const double m = mesh.units().origin_m[axis] + mesh.units().tick_m * ticks;
    return axis == 2 && options.z_up ? mesh.top_elevation() - m : m;
  }
  // VTK's and Gmsh's hexahedron corner i as weaver's corner.
  int hex_corner(int i) const { return (options.z_up ? kVtkHexCornerZUp : kVtkHexCorner)[i]; }
  double length(uint32_t ticks) const {
    return options.units == ExportUnits::kTicks ? ticks : mesh.units().tick_m * ticks;
  }
  const char* unit_name() const { return options.units == ExportUnits::kTicks ? "ticks" : "m"; }
  // The mesh's place on the Earth, when it has one (construct --origin-geo).
  bool georeferenced(GeoFrame* g) const {
    return !mesh.units().geo.empty() && GeoFrame::parse(mesh.units().geo, g).ok();
  }
  // Longitude and latitude (degrees) of the point at ticks c.
  void lon_lat(const GeoTransform& g, Coord c, double* lon, double* lat) const {
    const Units& u = mesh.units();
    g.to_geo(u.origin_m[0] + u.tick_m * c.x, u.origin_m[1] + u.tick_m * c.y, lon, lat);
  }
};

// Calls fn for each node of the selection in local id order (id and anchors
// stay global ids: map them with job.local), anchors looked up if asked.
Status for_each_node(ExportJob& job, bool with_anchors,
                     const std::function<Status(const MeshNode&)>& fn);
// Calls fn for each selected element in id order; with_nodes, its corners
// are local node ids.  Counts elements in the result and ticks progress.
Status for_each_element(ExportJob& job, bool with_nodes,
                        const std::function<Status(const MeshElement&)>& fn);

// The parts of --parts N: the stored partition (`weaver partition`) when it
// has N parts, otherwise N ranges of consecutive element ids of equal count.
// ranges holds each part's range where parts are ranges (else it is empty);
// method says which.
Status export_parts(ExportJob& job, PartMap* map, std::vector<PartRun>* ranges,
                    std::string* method);
// export_parts' answer in one value, for the writers that take it whole.
struct Parts {
  PartMap map;
  std::vector<PartRun> ranges;
  std::string method;
};
inline Status export_parts(ExportJob& job, Parts* parts) {
  return export_parts(job, &parts->map, &parts->ranges, &parts->method);
}
// The selection of part p (and only its range, when parts are ranges).
Selection part_selection(const ExportJob& job, const PartMap& map,
                         const std::vector<PartRun>& ranges, uint32_t p);
inline Selection part_selection(const ExportJob& job, const Parts& parts, uint32_t p) {
  return part_selection(job, parts.map, parts.ranges, p);
}

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
Status write_pvtu(ExportJob& job);
Status write_msh(ExportJob& job);
Status write_metis_graph(ExportJob& job);
Status write_metis_mesh(ExportJob& job);
Status write_raw(ExportJob& job);

// raw's pieces, for export_raw_parts.cc: the files of the job's selection in
// dir (with each node's sharing parts when shared is set), and the directory
// built as OUT.tmp and renamed to OUT when `written` is OK (else removed).
class SharedNodes;
Status write_raw_files(ExportJob& job, const std::string& dir, SharedNodes* shared);
Status start_export_dir(const std::string& out, std::string* tmp);
Status finish_export_dir(ExportJob& job, const std::string& tmp, const std::string& out,
                         Status written);
Status write_raw_parts(ExportJob& job);
// export_one_part and export_parts_end of export.h, per format.
Status write_raw_one_part(ExportJob& job, uint32_t p);
Status finish_raw_parts(ExportJob& job, bool written);
Status start_pvtu_parts(const ExportOptions& options);
Status write_pvtu_one_part(ExportJob& job, uint32_t p);
Status finish_pvtu_parts(ExportJob& job, bool written);

}  // namespace weaver
