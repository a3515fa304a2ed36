#include "export/boundary_faces.h"

#include <algorithm>

#include "db/boundary_table.h"
#include "schema/node.h"

namespace weaver {

Status for_each_boundary(ExportJob& job, const std::function<Status(const BoundaryRecord&)>& fn) {
  BTree& table = job.mesh.boundary();
  BTreeCursor c;
  WEAVER_RETURN_IF_ERROR(table.seek_cursor(0, &c));
  uint64_t local = 0;
  return scan_selected(job.mesh, job.sel, false, [&](MeshElement& e) {
    // Forward to e's records: a few steps, or a seek past a gap (a box).
    for (int steps = 0; c.valid() && boundary_element(c.key()) < e.id; ++steps) {
      if (steps == 16) {
        WEAVER_RETURN_IF_ERROR(table.seek_cursor(boundary_key(e.id, 0, 0), &c));
        break;
      }
      WEAVER_RETURN_IF_ERROR(c.next());
    }
    BoundaryRecord r;
    r.element = local++;
    r.global = e.id;
    r.octant = e.octant;
    r.mesh_element = &e;
    while (c.valid() && boundary_element(c.key()) == e.id) {
      r.face = boundary_face(c.key());
      r.part = boundary_part(c.key());
      r.kind = static_cast<uint8_t>(c.payload()[0]);
      WEAVER_RETURN_IF_ERROR(fn(r));
      WEAVER_RETURN_IF_ERROR(c.next());
    }
    return Status::Ok();
  });
}

Status count_boundary(ExportJob& job, uint64_t* n) {
  *n = 0;
  if (!job.mesh.has_boundary()) return Status::Ok();
  if (job.sel.whole()) {
    *n = job.mesh.boundary().size();
    return Status::Ok();
  }
  return for_each_boundary(job, [&](const BoundaryRecord&) {
    ++*n;
    return Status::Ok();
  });
}

std::array<Coord, 4> boundary_quad(const Octant& o, int face, int part) {
  const uint32_t e = octant_edge(o), c[3] = {o.x, o.y, o.z};
  const int a = face / 2, side = face & 1;
  const int u = a == 0 ? 1 : 0, v = a == 2 ? 1 : 2;
  uint32_t lo[3] = {c[0], c[1], c[2]}, span = e;
  lo[a] += side * e;
  if (part > 0) {
    span = e / 2;
    lo[u] += ((part - 1) & 1) * span;
    lo[v] += ((part - 1) >> 1) * span;
  }
  // (u, v) counter-clockwise is outward for a high face of a right-handed
  // (a, u, v); the low faces and the y faces' (x, z) turn the other way.
  const bool flip = (side == 0) != (a == 1);
  const int du[4] = {0, 1, 1, 0}, dv[4] = {0, 0, 1, 1};
  std::array<Coord, 4> q;
  for (int k = 0; k < 4; ++k) {
    const int i = flip ? (4 - k) % 4 : k;
    uint32_t p[3] = {lo[0], lo[1], lo[2]};
    p[u] += du[i] * span;
    p[v] += dv[i] * span;
    q[k] = {p[0], p[1], p[2]};
  }
  return q;
}

std::string boundary_vtu_path(const std::string& out) {
  const bool suffix = out.size() > 4 && out.compare(out.size() - 4, 4, ".vtu") == 0;
  return (suffix ? out.substr(0, out.size() - 4) : out) + "_boundary.vtu";
}

namespace {

struct QuadArray {
  const char* name;
  const char* type;
  int components;
  uint64_t bytes;
  uint64_t offset = 0;
};

std::string quad_array(const QuadArray& a) {
  std::string s = std::string("        <DataArray type=\"") + a.type + "\" Name=\"" + a.name + "\"";
  if (a.components > 1) s += " NumberOfComponents=\"" + std::to_string(a.components) + "\"";
  return s + " format=\"appended\" offset=\"" + std::to_string(a.offset) + "\"/>\n";
}

}  // namespace

Status write_boundary_vtu(ExportJob& job, const std::string& path) {
  uint64_t n = 0;
  WEAVER_RETURN_IF_ERROR(count_boundary(job, &n));
  enum { kElement, kFace, kPart, kKind, kPoints, kConn, kOffsets, kTypes, kCount };
  std::vector<QuadArray> a = {
      {"element_id", "Int64", 1, 8 * n}, {"face", "UInt8", 1, n},
      {"part", "UInt8", 1, n},           {"kind", "UInt8", 1, n},
      {"Points", "Float64", 3, 96 * n},  {"connectivity", "Int64", 1, 32 * n},
      {"offsets", "Int64", 1, 8 * n},    {"types", "UInt8", 1, n}};
  uint64_t at = 0;
  for (QuadArray& x : a) x.offset = at, at += 8 + x.bytes;
  std::string head =
      "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" "
      "byte_order=\"LittleEndian\" header_type=\"UInt64\">\n  <UnstructuredGrid>\n"
      "    <Piece NumberOfPoints=\"" +
      std::to_string(4 * n) + "\" NumberOfCells=\"" + std::to_string(n) + "\">\n";
  head += "      <CellData>\n" + quad_array(a[kElement]) + quad_array(a[kFace]) +
          quad_array(a[kPart]) + quad_array(a[kKind]) + "      </CellData>\n";
  head += "      <Points>\n" + quad_array(a[kPoints]) + "      </Points>\n";
  head += "      <Cells>\n" + quad_array(a[kConn]) + quad_array(a[kOffsets]) +
          quad_array(a[kTypes]) +
          "      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n  <AppendedData "
          "encoding=\"raw\">\n_";
  OutputFile file(path);
  WEAVER_RETURN_IF_ERROR(file.open());
  WEAVER_RETURN_IF_ERROR(file.write_at(0, head.data(), head.size()));
  std::vector<Section> out;
  for (const QuadArray& x : a) out.emplace_back(file, head.size() + x.offset, job.section_buffer);
  for (int i = 0; i < kCount; ++i) WEAVER_RETURN_IF_ERROR(out[i].value(a[i].bytes));
  int64_t quads = 0;
  if (n > 0) {
    WEAVER_RETURN_IF_ERROR(for_each_boundary(job, [&](const BoundaryRecord& r) {
      WEAVER_RETURN_IF_ERROR(out[kElement].value(int64_t(r.global)));
      WEAVER_RETURN_IF_ERROR(out[kFace].value(uint8_t(r.face)));
      WEAVER_RETURN_IF_ERROR(out[kPart].value(uint8_t(r.part)));
      WEAVER_RETURN_IF_ERROR(out[kKind].value(r.kind));
      std::array<Coord, 4> q = boundary_quad(r.octant, r.face, r.part);
      if (job.options.z_up) std::reverse(q.begin(), q.end());  // z mirrored: still outward
      for (const Coord& p : q) {
        const double xyz[3] = {job.coord(0, p.x), job.coord(1, p.y), job.coord(2, p.z)};
        WEAVER_RETURN_IF_ERROR(out[kPoints].put(xyz, sizeof xyz));
      }
      const int64_t conn[4] = {4 * quads, 4 * quads + 1, 4 * quads + 2, 4 * quads + 3};
      WEAVER_RETURN_IF_ERROR(out[kConn].put(conn, sizeof conn));
      WEAVER_RETURN_IF_ERROR(out[kOffsets].value(int64_t(4 * ++quads)));
      return out[kTypes].value(uint8_t(9));  // VTK_QUAD
    }));
  }
  for (Section& s : out) WEAVER_RETURN_IF_ERROR(s.flush());
  const std::string tail = "\n  </AppendedData>\n</VTKFile>\n";
  WEAVER_RETURN_IF_ERROR(file.write_at(head.size() + at, tail.data(), tail.size()));
  job.result->bytes += head.size() + at + tail.size();
  return file.finish();
}

Status MshBoundary::tag_of(ExportJob& job, Coord c, uint64_t* tag, bool* extra) const {
  uint64_t global = 0, local = 0;
  bool present = false;
  WEAVER_RETURN_IF_ERROR(job.mesh.nodes().rank_exact(node_key(c), &global, &present));
  *extra = !present || !job.local->local_id(global, &local).ok();
  if (!*extra) {
    *tag = local + 1;
    return Status::Ok();
  }
  const auto it = std::lower_bound(extra_.begin(), extra_.end(), node_key(c));
  *tag = nodes_ + 1 + uint64_t(it - extra_.begin());
  return Status::Ok();
}

Status MshBoundary::plan(ExportJob& job) {
  present_ = job.mesh.has_boundary();
  if (!present_) return Status::Ok();
  nodes_ = job.node_count();
  std::vector<uint64_t> found;
  WEAVER_RETURN_IF_ERROR(for_each_boundary(job, [&](const BoundaryRecord& r) {
    ++counts_[r.kind != 0];
    if (r.part == 0) return Status::Ok();  // an element's own corners
    for (const Coord& c : boundary_quad(r.octant, r.face, r.part)) {
      uint64_t tag;
      bool extra = false;
      WEAVER_RETURN_IF_ERROR(tag_of(job, c, &tag, &extra));
      if (extra) found.push_back(node_key(c));
    }
    return Status::Ok();
  }));
  std::sort(found.begin(), found.end());
  found.erase(std::unique(found.begin(), found.end()), found.end());
  extra_ = std::move(found);
  return Status::Ok();
}

std::string MshBoundary::head() const {
  std::string s =
      "$PhysicalNames\n3\n2 1 \"free_surface\"\n2 2 \"absorbing\"\n3 3 \"volume\"\n"
      "$EndPhysicalNames\n";
  // No points or curves; surfaces 1 (free surface) and 2 (absorbing), volume
  // 1: tag, a box (Gmsh recomputes it), physical tags, bounding entities.
  return s + "$Entities\n0 0 2 1\n1 0 0 0 0 0 0 1 1 0\n2 0 0 0 0 0 0 1 2 0\n" +
         "1 0 0 0 0 0 0 1 3 0\n$EndEntities\n";
}

Status MshBoundary::write_extra_nodes(ExportJob& job, Section& out, uint64_t first_tag) const {
  WEAVER_RETURN_IF_ERROR(out.text("2 1 0 " + std::to_string(extra_.size()) + "\n"));
  LineBuffer line;
  for (uint64_t i = 0; i < extra_.size(); ++i) line.field(first_tag + i), line.ch('\n');
  WEAVER_RETURN_IF_ERROR(line.emit(out));
  for (uint64_t key : extra_) {
    const Coord c = morton_decode(key);
    line.field(job.coord(0, c.x)), line.ch(' '), line.field(job.coord(1, c.y)), line.ch(' ');
    line.field(job.coord(2, c.z)), line.ch('\n');
    WEAVER_RETURN_IF_ERROR(line.emit(out));
  }
  return Status::Ok();
}

Status MshBoundary::for_each_quad(ExportJob& job, int kind,
                                  const std::function<Status(const MeshElement&)>& fn) {
  return for_each_boundary(job, [&](const BoundaryRecord& r) {
    return (r.kind != 0) == (kind != 0) ? fn(*r.mesh_element) : Status::Ok();
  });
}

Status MshBoundary::write_quads(ExportJob& job, Section& out, int kind, uint64_t* tag) {
  const int entity = kind == 1 ? 1 : 2;
  WEAVER_RETURN_IF_ERROR(
      out.text("2 " + std::to_string(entity) + " 3 " + std::to_string(counts_[kind != 0]) + "\n"));
  LineBuffer line;
  return for_each_boundary(job, [&](const BoundaryRecord& r) {
    if ((r.kind != 0) != (kind != 0)) return Status::Ok();
    line.field(++*tag);
    std::array<Coord, 4> q = boundary_quad(r.octant, r.face, r.part);
    if (job.options.z_up) std::reverse(q.begin(), q.end());  // z mirrored: still outward
    for (const Coord& c : q) {
      uint64_t t = 0;
      bool extra = false;
      WEAVER_RETURN_IF_ERROR(tag_of(job, c, &t, &extra));
      line.ch(' '), line.field(t);
    }
    line.ch('\n');
    return line.emit(out);
  });
}

}  // namespace weaver
