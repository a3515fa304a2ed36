// vtu: VTK's XML UnstructuredGrid (file format version 1.0), one piece, the
// arrays as raw binary appended data, each preceded by its byte count as a
// UInt64 (header_type="UInt64").  Every array's size follows from the node
// and element counts, so the XML header with all offsets is written first
// and each array streams into its own section of the file: one pass over the
// nodes, one over the elements.
//
//   PointData  node_id Int64, kind UInt8 (0 anchored, 1 edge, 2 face)
//   CellData   element_id Int64, level UInt8, edge Float64 (in the units),
//              vp vs rho Float32 (when the mesh has material)
//   Points     Float64 x 3 (metres by default, or ticks)
//   Cells      connectivity Int64 (VTK's corner order), offsets Int64,
//              types UInt8 (12, VTK_HEXAHEDRON)
#include <vector>

#include "export/writers.h"

namespace weaver {
namespace {

constexpr uint8_t kVtkHexahedron = 12;

struct Array {
  const char* name;
  const char* type;  // VTK's name of the element type
  int components;
  uint64_t bytes;  // of data, without the count before it
  uint64_t offset = 0;
};

// Arrays in file order; the index names each one below.
enum : int {
  kNodeId,
  kKind,
  kElementId,
  kLevel,
  kEdge,
  kVp,
  kVs,
  kRho,
  kPoints,
  kConn,
  kOffsets,
  kTypes,
  kArrays
};

std::vector<Array> layout(uint64_t n, uint64_t e) {
  std::vector<Array> a = {{"node_id", "Int64", 1, 8 * n},    {"kind", "UInt8", 1, n},
                          {"element_id", "Int64", 1, 8 * e}, {"level", "UInt8", 1, e},
                          {"edge", "Float64", 1, 8 * e},     {"vp", "Float32", 1, 4 * e},
                          {"vs", "Float32", 1, 4 * e},       {"rho", "Float32", 1, 4 * e},
                          {"Points", "Float64", 3, 24 * n},  {"connectivity", "Int64", 1, 64 * e},
                          {"offsets", "Int64", 1, 8 * e},    {"types", "UInt8", 1, e}};
  uint64_t at = 0;
  for (Array& x : a) x.offset = at, at += 8 + x.bytes;
  return a;
}

std::string data_array(const Array& a) {
  std::string s = "        <DataArray type=\"" + std::string(a.type) + "\" Name=\"" + a.name + "\"";
  if (a.components > 1) s += " NumberOfComponents=\"" + std::to_string(a.components) + "\"";
  return s + " format=\"appended\" offset=\"" + std::to_string(a.offset) + "\"/>\n";
}

std::string header(const std::vector<Array>& a, uint64_t n, uint64_t e, bool material) {
  std::string s =
      "<?xml version=\"1.0\"?>\n"
      "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" "
      "header_type=\"UInt64\">\n"
      "  <UnstructuredGrid>\n"
      "    <Piece NumberOfPoints=\"" +
      std::to_string(n) + "\" NumberOfCells=\"" + std::to_string(e) + "\">\n";
  s += "      <PointData>\n" + data_array(a[kNodeId]) + data_array(a[kKind]) +
       "      </PointData>\n";
  s += "      <CellData>\n" + data_array(a[kElementId]) + data_array(a[kLevel]) +
       data_array(a[kEdge]);
  if (material) s += data_array(a[kVp]) + data_array(a[kVs]) + data_array(a[kRho]);
  s += "      </CellData>\n      <Points>\n" + data_array(a[kPoints]) + "      </Points>\n";
  s += "      <Cells>\n" + data_array(a[kConn]) + data_array(a[kOffsets]) + data_array(a[kTypes]) +
       "      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n  <AppendedData encoding=\"raw\">\n_";
  return s;
}

// One section per array, starting at its byte count.
struct Sections {
  std::vector<Section> s;
  Sections(OutputFile& f, const std::vector<Array>& a, uint64_t base, size_t buffer) {
    for (const Array& x : a) s.emplace_back(f, base + x.offset, buffer);
  }
  Section& operator[](int i) { return s[i]; }
};

Status write_nodes(ExportJob& job, Sections& out) {
  NodeScan scan;
  WEAVER_RETURN_IF_ERROR(scan.start(job.mesh, false));
  for (; scan.valid(); scan.next()) {
    const MeshNode& n = scan.node();
    WEAVER_RETURN_IF_ERROR(out[kNodeId].value(int64_t(n.id)));
    WEAVER_RETURN_IF_ERROR(out[kKind].value(uint8_t(n.kind)));
    const double p[3] = {job.coord(0, n.c.x), job.coord(1, n.c.y), job.coord(2, n.c.z)};
    WEAVER_RETURN_IF_ERROR(out[kPoints].put(p, sizeof p));
    ++job.result->nodes;
    job.tick();
  }
  WEAVER_RETURN_IF_ERROR(scan.status());
  return Status::Ok();
}

Status write_elements(ExportJob& job, Sections& out, bool material) {
  ElementScan scan;
  WEAVER_RETURN_IF_ERROR(scan.start(job.mesh));
  for (; scan.valid(); scan.next()) {
    const MeshElement& e = scan.element();
    WEAVER_RETURN_IF_ERROR(out[kElementId].value(int64_t(e.id)));
    WEAVER_RETURN_IF_ERROR(out[kLevel].value(uint8_t(e.octant.level)));
    WEAVER_RETURN_IF_ERROR(out[kEdge].value(job.length(octant_edge(e.octant))));
    if (material) {
      WEAVER_RETURN_IF_ERROR(out[kVp].value(e.vp));
      WEAVER_RETURN_IF_ERROR(out[kVs].value(e.vs));
      WEAVER_RETURN_IF_ERROR(out[kRho].value(e.rho));
    }
    int64_t conn[8];
    for (int i = 0; i < 8; ++i) conn[i] = int64_t(e.nodes[kVtkHexCorner[i]]);
    WEAVER_RETURN_IF_ERROR(out[kConn].put(conn, sizeof conn));
    WEAVER_RETURN_IF_ERROR(out[kOffsets].value(int64_t(8 * (e.id + 1))));
    WEAVER_RETURN_IF_ERROR(out[kTypes].value(kVtkHexahedron));
    ++job.result->elements;
    job.tick();
  }
  WEAVER_RETURN_IF_ERROR(scan.status());
  return Status::Ok();
}

}  // namespace

Status write_vtu(ExportJob& job) {
  const uint64_t n = job.mesh.node_count(), e = job.mesh.element_count();
  const bool material = job.mesh.has_material();
  std::vector<Array> arrays = layout(n, e);
  if (!material) {  // no vp, vs, rho: the later arrays move up
    const uint64_t gap = arrays[kPoints].offset - arrays[kVp].offset;
    for (int i = kVp; i <= kRho; ++i) arrays[i].bytes = 0;
    for (int i = kPoints; i < kArrays; ++i) arrays[i].offset -= gap;
  }
  const std::string head = header(arrays, n, e, material);
  OutputFile file(job.options.out);
  WEAVER_RETURN_IF_ERROR(file.open());
  WEAVER_RETURN_IF_ERROR(file.write_at(0, head.data(), head.size()));
  const uint64_t base = head.size();
  Sections out(file, arrays, base, job.section_buffer);
  for (int i = 0; i < kArrays; ++i) {
    if (!material && i >= kVp && i <= kRho) continue;
    WEAVER_RETURN_IF_ERROR(out[i].value(arrays[i].bytes));
  }
  job.plan(n + e);
  WEAVER_RETURN_IF_ERROR(write_nodes(job, out));
  WEAVER_RETURN_IF_ERROR(write_elements(job, out, material));
  for (Section& s : out.s) WEAVER_RETURN_IF_ERROR(s.flush());
  const Array& last = arrays[kTypes];
  const std::string tail = "\n  </AppendedData>\n</VTKFile>\n";
  const uint64_t end = base + last.offset + 8 + last.bytes;
  WEAVER_RETURN_IF_ERROR(file.write_at(end, tail.data(), tail.size()));
  job.result->bytes += end + tail.size();
  return file.finish();
}

}  // namespace weaver
