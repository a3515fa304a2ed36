// vtu: VTK's XML UnstructuredGrid (file format version 1.0), one piece, the
// arrays as raw binary appended data, each preceded by its byte count as a
// UInt64 (header_type="UInt64").  Every array's size follows from the node
// and element counts, so the XML header with all offsets is written first
// and each array streams into its own section of the file: one pass over the
// nodes, one over the elements.
//
//   PointData  node_id Int64 (global ids), kind UInt8 (0 anchored, 1 edge, 2 face),
//              longitude latitude Float64 (WGS84 degrees, when georeferenced)
//   CellData   element_id Int64 (global ids), level UInt8, edge Float64 (in
//              the units), vp vs rho Float32 (when the mesh has material),
//              qp qs Float32 (when its material has them), solid_fraction
//              Float32 (a mesh built with --surface: the share below ground)
//   FieldData  top_elevation_m Float64 (a mesh built with --surface)
//   Points     Float64 x 3 (metres by default, or ticks)
//   Cells      connectivity Int64 (VTK's corner order), offsets Int64,
//              types UInt8 (12, VTK_HEXAHEDRON)
//
// pvtu: the elements cut into --parts pieces (the parts of export_parts:
// the stored partition, or consecutive ids in equal counts), each a vtu of the nodes it uses, in
// the directory STEM/ beside STEM.pvtu, the index ParaView opens; written last, so an index is
// never left pointing at missing pieces.
#include <sys/stat.h>

#include <vector>

#include "export/boundary_faces.h"
#include "export/writers.h"

namespace weaver {

std::string pvtu_stem(const std::string& out) {
  const bool suffix = out.size() > 5 && out.compare(out.size() - 5, 5, ".pvtu") == 0;
  return suffix ? out.substr(0, out.size() - 5) : out;
}

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
  kLon,
  kLat,
  kElementId,
  kLevel,
  kEdge,
  kVp,
  kVs,
  kRho,
  kQp,
  kQs,
  kSolid,
  kPoints,
  kConn,
  kOffsets,
  kTypes,
  kArrays
};

// The optional arrays: which the mesh has.
struct Present {
  bool material = false, q = false, geo = false, solid = false;
  bool operator()(int i) const {
    return (material || i < kVp || i > kRho) && (q || (i != kQp && i != kQs)) &&
           (geo || (i != kLon && i != kLat)) && (solid || i != kSolid);
  }
};

// Which optional arrays the job's mesh has; *geo its frame when georeferenced.
Present present(ExportJob& job, GeoFrame* geo) {
  return {job.mesh.has_material(), job.mesh.has_q(), job.georeferenced(geo), job.mesh.has_solid()};
}

// Arrays the mesh does not have (vp, vs, rho without material; qp, qs
// without Q; longitude, latitude when not georeferenced) take no bytes and
// are not declared.
std::vector<Array> layout(uint64_t n, uint64_t e, Present has) {
  const uint64_t m = has.material ? 4 * e : 0, q = has.q ? 4 * e : 0, g = has.geo ? 8 * n : 0;
  const uint64_t solid = has.solid ? 4 * e : 0;
  std::vector<Array> a = {{"node_id", "Int64", 1, 8 * n},
                          {"kind", "UInt8", 1, n},
                          {"longitude", "Float64", 1, g},
                          {"latitude", "Float64", 1, g},
                          {"element_id", "Int64", 1, 8 * e},
                          {"level", "UInt8", 1, e},
                          {"edge", "Float64", 1, 8 * e},
                          {"vp", "Float32", 1, m},
                          {"vs", "Float32", 1, m},
                          {"rho", "Float32", 1, m},
                          {"qp", "Float32", 1, q},
                          {"qs", "Float32", 1, q},
                          {"solid_fraction", "Float32", 1, solid},
                          {"Points", "Float64", 3, 24 * n},
                          {"connectivity", "Int64", 1, 64 * e},
                          {"offsets", "Int64", 1, 8 * e},
                          {"types", "UInt8", 1, e}};
  uint64_t at = 0;
  for (int i = 0; i < kArrays; ++i) {
    if (has(i)) a[i].offset = at, at += 8 + a[i].bytes;
  }
  return a;
}

// A DataArray element; `p` for the PDataArray of a pvtu (no data).
std::string data_array(const Array& a, bool p = false) {
  std::string s = std::string(p ? "      <PDataArray" : "        <DataArray") + " type=\"" +
                  a.type + "\" Name=\"" + a.name + "\"";
  if (a.components > 1) s += " NumberOfComponents=\"" + std::to_string(a.components) + "\"";
  if (p) return s + "/>\n";
  return s + " format=\"appended\" offset=\"" + std::to_string(a.offset) + "\"/>\n";
}

// The point data, cell data and points declarations, as a vtu or pvtu has them.
std::string declarations(const std::vector<Array>& a, Present has, bool p) {
  const std::string in = p ? "    <P" : "      <", out = p ? "    </P" : "      </";
  std::string s = in + "PointData>\n" + data_array(a[kNodeId], p) + data_array(a[kKind], p);
  if (has.geo) s += data_array(a[kLon], p) + data_array(a[kLat], p);
  s += out + "PointData>\n";
  s += in + "CellData>\n" + data_array(a[kElementId], p) + data_array(a[kLevel], p) +
       data_array(a[kEdge], p);
  if (has.material) s += data_array(a[kVp], p) + data_array(a[kVs], p) + data_array(a[kRho], p);
  if (has.q) s += data_array(a[kQp], p) + data_array(a[kQs], p);
  if (has.solid) s += data_array(a[kSolid], p);
  return s + out + "CellData>\n" + in + "Points>\n" + data_array(a[kPoints], p) + out + "Points>\n";
}

constexpr char kVtkFile[] = "<?xml version=\"1.0\"?>\n<VTKFile type=\"";
constexpr char kVtkFileEnd[] =
    "\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n";

// The mesh's own facts as field data: the top's elevation of a mesh built
// under a ground (z = 0 there), for readers that turn depth into elevation.
std::string field_data(const Mesh& m) {
  if (!m.has_ground()) return "";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.17g", m.top_elevation());
  return std::string(
             "    <FieldData>\n      <DataArray type=\"Float64\" Name=\"top_elevation_m\" "
             "NumberOfTuples=\"1\" format=\"ascii\">") +
         buf + "</DataArray>\n    </FieldData>\n";
}

std::string header(const std::vector<Array>& a, uint64_t n, uint64_t e, Present has,
                   const std::string& fields) {
  std::string s = std::string(kVtkFile) + "UnstructuredGrid" + kVtkFileEnd +
                  "  <UnstructuredGrid>\n" + fields + "    <Piece NumberOfPoints=\"" +
                  std::to_string(n) + "\" NumberOfCells=\"" + std::to_string(e) + "\">\n";
  s += declarations(a, has, false);
  s += "      <Cells>\n" + data_array(a[kConn]) + data_array(a[kOffsets]) + data_array(a[kTypes]) +
       "      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n  <AppendedData encoding=\"raw\">\n_";
  return s;
}

Status write_points(ExportJob& job, std::vector<Section>& out, const GeoTransform* geo) {
  return for_each_node(job, false, [&](const MeshNode& n) {
    WEAVER_RETURN_IF_ERROR(out[kNodeId].value(int64_t(n.id)));
    WEAVER_RETURN_IF_ERROR(out[kKind].value(uint8_t(n.kind)));
    if (geo) {
      double lon, lat;
      job.lon_lat(*geo, n.c, &lon, &lat);
      WEAVER_RETURN_IF_ERROR(out[kLon].value(lon));
      WEAVER_RETURN_IF_ERROR(out[kLat].value(lat));
    }
    const double p[3] = {job.coord(0, n.c.x), job.coord(1, n.c.y), job.coord(2, n.c.z)};
    return out[kPoints].put(p, sizeof p);
  });
}

Status write_cells(ExportJob& job, std::vector<Section>& out, Present has) {
  int64_t cells = 0;
  return for_each_element(job, true, [&](const MeshElement& e) {
    WEAVER_RETURN_IF_ERROR(out[kElementId].value(int64_t(e.id)));
    WEAVER_RETURN_IF_ERROR(out[kLevel].value(uint8_t(e.octant.level)));
    WEAVER_RETURN_IF_ERROR(out[kEdge].value(job.length(octant_edge(e.octant))));
    if (has.material) {
      WEAVER_RETURN_IF_ERROR(out[kVp].value(e.vp));
      WEAVER_RETURN_IF_ERROR(out[kVs].value(e.vs));
      WEAVER_RETURN_IF_ERROR(out[kRho].value(e.rho));
    }
    if (has.solid) WEAVER_RETURN_IF_ERROR(out[kSolid].value(e.solid));
    if (has.q) {
      WEAVER_RETURN_IF_ERROR(out[kQp].value(e.qp));
      WEAVER_RETURN_IF_ERROR(out[kQs].value(e.qs));
    }
    int64_t conn[8];
    for (int i = 0; i < 8; ++i) conn[i] = int64_t(e.nodes[job.hex_corner(i)]);
    WEAVER_RETURN_IF_ERROR(out[kConn].put(conn, sizeof conn));
    WEAVER_RETURN_IF_ERROR(out[kOffsets].value(int64_t(8 * ++cells)));
    return out[kTypes].value(kVtkHexahedron);
  });
}

// One vtu of the job's selection.
Status write_vtu_file(ExportJob& job, const std::string& path) {
  const uint64_t n = job.node_count(), e = job.element_count();
  GeoFrame geo;
  const Present has = present(job, &geo);
  const GeoTransform transform(geo);
  const std::vector<Array> arrays = layout(n, e, has);
  const std::string head = header(arrays, n, e, has, field_data(job.mesh));
  OutputFile file(path);
  WEAVER_RETURN_IF_ERROR(file.open());
  WEAVER_RETURN_IF_ERROR(file.write_at(0, head.data(), head.size()));
  const uint64_t base = head.size();
  std::vector<Section> out;
  for (const Array& a : arrays) out.emplace_back(file, base + a.offset, job.section_buffer);
  for (int i = 0; i < kArrays; ++i) {
    if (has(i)) WEAVER_RETURN_IF_ERROR(out[i].value(arrays[i].bytes));
  }
  WEAVER_RETURN_IF_ERROR(write_points(job, out, has.geo ? &transform : nullptr));
  WEAVER_RETURN_IF_ERROR(write_cells(job, out, has));
  for (Section& s : out) WEAVER_RETURN_IF_ERROR(s.flush());
  const Array& last = arrays[kTypes];
  const std::string tail = "\n  </AppendedData>\n</VTKFile>\n";
  const uint64_t end = base + last.offset + 8 + last.bytes;
  WEAVER_RETURN_IF_ERROR(file.write_at(end, tail.data(), tail.size()));
  job.result->bytes += end + tail.size();
  return file.finish();
}

std::string base_name(const std::string& path) {
  const size_t slash = path.rfind('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

}  // namespace

Status write_vtu(ExportJob& job) {
  job.plan(job.node_count() + job.element_count());
  if (job.options.has_box) {
    Selection s;
    WEAVER_RETURN_IF_ERROR(job.box_selection(&s));
    if (job.options.max_elements > 0) {
      uint64_t n = 0;
      WEAVER_RETURN_IF_ERROR(count_box_elements(job.mesh, s, &n));
      if (n > job.options.max_elements) {
        job.result->elements = n;
        return Status::InvalidArgument(std::to_string(n) +
                                       " elements share a point with the box, more than " +
                                       std::to_string(job.options.max_elements));
      }
    }
    WEAVER_RETURN_IF_ERROR(job.select(s, false, job.options.out + ".scratch"));
  }
  WEAVER_RETURN_IF_ERROR(write_vtu_file(job, job.options.out));
  // The boundary beside the mesh, so that readers of the mesh see no change.
  if (!job.mesh.has_boundary()) return Status::Ok();
  return write_boundary_vtu(job, boundary_vtu_path(job.options.out));
}

namespace {

std::string piece_name(const std::string& stem, uint32_t p) {
  return base_name(stem) + "/" + base_name(stem) + "_" + std::to_string(p) + ".vtu";
}

Status make_stem_dir(const std::string& stem) {
  if (::mkdir(stem.c_str(), 0755) != 0 && errno != EEXIST) {
    return Status::IOError("cannot create directory " + stem + ": " + std::strerror(errno));
  }
  return Status::Ok();
}

// The parts of the pieces, and the box they are cut to (if any).
Status plan_pieces(ExportJob& job, Parts* parts, Selection* box) {
  WEAVER_RETURN_IF_ERROR(export_parts(job, parts));
  return job.options.has_box ? job.box_selection(box) : Status::Ok();
}

// Piece p of the parts (within the box, if any).
Status write_piece(ExportJob& job, const Parts& parts, const Selection& box, uint32_t p) {
  Selection s = part_selection(job, parts, p);
  s.has_box = box.has_box, s.lo = box.lo, s.hi = box.hi;
  WEAVER_RETURN_IF_ERROR(job.select(s, false, job.options.out + ".scratch-" + std::to_string(p)));
  const std::string stem = pvtu_stem(job.options.out);
  const std::string piece = stem + "/" + base_name(piece_name(stem, p));
  WEAVER_RETURN_IF_ERROR(write_vtu_file(job, piece));
  // The piece's boundary beside it (boundary_faces.h), named by its own index.
  if (!job.mesh.has_boundary()) return Status::Ok();
  return write_boundary_vtu(job, boundary_vtu_path(piece));
}

// STEM_boundary.pvtu: the pieces' boundary quads, for ParaView to open
// beside STEM.pvtu.
Status write_boundary_index(ExportJob& job) {
  const std::string stem = pvtu_stem(job.options.out);
  std::string pieces;
  for (uint32_t p = 0; p < job.options.parts; ++p) {
    pieces += "    <Piece Source=\"" + boundary_vtu_path(piece_name(stem, p)) + "\"/>\n";
  }
  const std::string index =
      std::string(kVtkFile) + "PUnstructuredGrid" + kVtkFileEnd +
      "  <PUnstructuredGrid GhostLevel=\"0\">\n    <PCellData>\n"
      "      <PDataArray type=\"Int64\" Name=\"element_id\"/>\n"
      "      <PDataArray type=\"UInt8\" Name=\"face\"/>\n"
      "      <PDataArray type=\"UInt8\" Name=\"part\"/>\n"
      "      <PDataArray type=\"UInt8\" Name=\"kind\"/>\n    </PCellData>\n    <PPoints>\n"
      "      <PDataArray type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\"/>\n"
      "    </PPoints>\n" +
      pieces + "  </PUnstructuredGrid>\n</VTKFile>\n";
  OutputFile file(stem + "_boundary.pvtu");
  WEAVER_RETURN_IF_ERROR(file.open());
  WEAVER_RETURN_IF_ERROR(file.write_at(0, index.data(), index.size()));
  job.result->bytes += index.size();
  return file.finish();
}

// The index ParaView opens, naming every piece: written last (after the
// boundary's index, where the mesh has a boundary table).
Status write_pvtu_index(ExportJob& job) {
  if (job.mesh.has_boundary()) WEAVER_RETURN_IF_ERROR(write_boundary_index(job));
  const std::string stem = pvtu_stem(job.options.out);
  std::string pieces;
  for (uint32_t p = 0; p < job.options.parts; ++p) {
    pieces += "    <Piece Source=\"" + piece_name(stem, p) + "\"/>\n";
  }
  GeoFrame geo;
  const Present has = present(job, &geo);
  const std::string index = std::string(kVtkFile) + "PUnstructuredGrid" + kVtkFileEnd +
                            "  <PUnstructuredGrid GhostLevel=\"0\">\n" +
                            declarations(layout(0, 0, has), has, true) + pieces +
                            "  </PUnstructuredGrid>\n</VTKFile>\n";
  OutputFile file(job.options.out);
  WEAVER_RETURN_IF_ERROR(file.open());
  WEAVER_RETURN_IF_ERROR(file.write_at(0, index.data(), index.size()));
  job.result->bytes += index.size();
  return file.finish();
}

}  // namespace

Status write_pvtu(ExportJob& job) {
  WEAVER_RETURN_IF_ERROR(make_stem_dir(pvtu_stem(job.options.out)));
  job.plan(job.mesh.node_count() + job.mesh.element_count());
  Parts parts;
  Selection box;
  WEAVER_RETURN_IF_ERROR(plan_pieces(job, &parts, &box));
  for (uint32_t p = 0; p < job.options.parts; ++p) {
    WEAVER_RETURN_IF_ERROR(write_piece(job, parts, box, p));
  }
  return write_pvtu_index(job);
}

Status start_pvtu_parts(const ExportOptions& options) {
  return make_stem_dir(pvtu_stem(options.out));
}

Status write_pvtu_one_part(ExportJob& job, uint32_t p) {
  job.plan((job.mesh.node_count() + job.mesh.element_count()) / job.options.parts);
  Parts parts;
  Selection box;
  WEAVER_RETURN_IF_ERROR(plan_pieces(job, &parts, &box));
  return write_piece(job, parts, box, p);
}

Status finish_pvtu_parts(ExportJob& job, bool written) {
  if (!written) return Status::Ok();  // the pieces written stay; no index names them
  return write_pvtu_index(job);
}

}  // namespace weaver
