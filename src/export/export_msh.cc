// msh: Gmsh's MSH 4.1, ASCII.  One node block and one element block (entity
// 3 of dimension 3), hexahedra (type 5) in Gmsh's corner order; with a
// boundary table, $PhysicalNames and $Entities too, and the boundary's
// quadrilaterals (type 3) in the physical groups free_surface and absorbing
// (boundary_faces.h: MshBoundary), the hexahedra in "volume"; then one $ElementData view per field:
// level, and vp, vs, rho when the mesh has material (and qp, qs when it has them).  Tags are
// 1-based positions: id + 1 for the whole mesh, the local id + 1 with --box.  Coordinates in metres
// by default, or ticks. Written in one sequential stream: a pass over the nodes for their tags, one
// for their coordinates, one over the elements for their corners, and one a field.
#include <string>

#include "export/boundary_faces.h"
#include "export/writers.h"

namespace weaver {
namespace {

constexpr int kGmshHexahedron = 5;

Status write_nodes(ExportJob& job, Section& out, const MshBoundary& b) {
  const uint64_t n = job.node_count(), all = n + b.extra_nodes();
  const std::string blocks = b.extra_nodes() > 0 ? "2 " : "1 ";
  WEAVER_RETURN_IF_ERROR(out.text("$Nodes\n" + blocks + std::to_string(all) + " 1 " +
                                  std::to_string(all) + "\n3 1 0 " + std::to_string(n) + "\n"));
  LineBuffer line;
  for (uint64_t tag = 1; tag <= n; ++tag) {
    line.field(tag), line.ch('\n');
    WEAVER_RETURN_IF_ERROR(line.emit(out));
  }
  WEAVER_RETURN_IF_ERROR(for_each_node(job, false, [&](const MeshNode& node) {
    const Coord c = node.c;
    line.field(job.coord(0, c.x)), line.ch(' '), line.field(job.coord(1, c.y)), line.ch(' ');
    line.field(job.coord(2, c.z)), line.ch('\n');
    return line.emit(out);
  }));
  if (b.extra_nodes() > 0) WEAVER_RETURN_IF_ERROR(b.write_extra_nodes(job, out, n + 1));
  return out.text("$EndNodes\n");
}

Status write_elements(ExportJob& job, Section& out, MshBoundary& b) {
  const uint64_t e = job.element_count(), all = e + b.quads(0) + b.quads(1);
  const int blocks = 1 + (b.quads(0) > 0) + (b.quads(1) > 0);
  WEAVER_RETURN_IF_ERROR(out.text("$Elements\n" + std::to_string(blocks) + " " +
                                  std::to_string(all) + " 1 " + std::to_string(all) + "\n3 1 " +
                                  std::to_string(kGmshHexahedron) + " " + std::to_string(e) +
                                  "\n"));
  LineBuffer line;
  uint64_t tag = 0;
  WEAVER_RETURN_IF_ERROR(for_each_element(job, true, [&](const MeshElement& el) {
    line.field(++tag);
    for (int i = 0; i < 8; ++i) line.ch(' '), line.field(el.nodes[job.hex_corner(i)] + 1);
    line.ch('\n');
    return line.emit(out);
  }));
  uint64_t quad = e;
  for (int kind : {1, 0}) {
    if (b.quads(kind) > 0) WEAVER_RETURN_IF_ERROR(b.write_quads(job, out, kind, &quad));
  }
  return out.text("$EndElements\n");
}

// A field's value of an element: 0 level, 1 vp, 2 vs, 3 rho, 4 qp, 5 qs.
void field_value(const MeshElement& el, int field, LineBuffer& line) {
  if (field == 0) {
    line.field(uint64_t{el.octant.level});
  } else {
    const float v[6] = {0, el.vp, el.vs, el.rho, el.qp, el.qs};
    line.field(double(v[field]));
  }
}

// One view of element data.  A boundary quad takes its element's value, so
// that every element has one (meshio reads a view as a value a cell).
Status write_element_data(ExportJob& job, Section& out, MshBoundary& b, const char* name,
                          int field) {
  const uint64_t all = job.element_count() + b.quads(0) + b.quads(1);
  WEAVER_RETURN_IF_ERROR(out.text(std::string("$ElementData\n1\n\"") + name +
                                  "\"\n1\n0\n3\n0\n1\n" + std::to_string(all) + "\n"));
  LineBuffer line;
  uint64_t tag = 0;
  WEAVER_RETURN_IF_ERROR(for_each_element(job, false, [&](const MeshElement& el) {
    line.field(++tag), line.ch(' ');
    field_value(el, field, line);
    line.ch('\n');
    return line.emit(out);
  }));
  for (int kind : {1, 0}) {
    if (b.quads(kind) == 0) continue;
    WEAVER_RETURN_IF_ERROR(b.for_each_quad(job, kind, [&](const MeshElement& el) {
      line.field(++tag), line.ch(' ');
      field_value(el, field, line);
      line.ch('\n');
      return line.emit(out);
    }));
  }
  return out.text("$EndElementData\n");
}

}  // namespace

Status write_msh(ExportJob& job) {
  if (job.options.has_box) {
    Selection s;
    WEAVER_RETURN_IF_ERROR(job.box_selection(&s));
    WEAVER_RETURN_IF_ERROR(job.select(s, false, job.options.out + ".scratch"));
  }
  const bool material = job.mesh.has_material();
  const bool q = job.mesh.has_q();
  job.plan(job.node_count() + job.element_count() * (material ? (q ? 7 : 5) : 2));
  OutputFile file(job.options.out);
  WEAVER_RETURN_IF_ERROR(file.open());
  Section out(file, 0, job.section_buffer * 4);
  MshBoundary boundary;
  WEAVER_RETURN_IF_ERROR(boundary.plan(job));
  WEAVER_RETURN_IF_ERROR(out.text("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"));
  if (boundary.present()) WEAVER_RETURN_IF_ERROR(out.text(boundary.head()));
  WEAVER_RETURN_IF_ERROR(write_nodes(job, out, boundary));
  WEAVER_RETURN_IF_ERROR(write_elements(job, out, boundary));
  const uint64_t elements = job.result->elements;  // the data views count none
  WEAVER_RETURN_IF_ERROR(write_element_data(job, out, boundary, "level", 0));
  if (material) {
    WEAVER_RETURN_IF_ERROR(write_element_data(job, out, boundary, "vp", 1));
    WEAVER_RETURN_IF_ERROR(write_element_data(job, out, boundary, "vs", 2));
    WEAVER_RETURN_IF_ERROR(write_element_data(job, out, boundary, "rho", 3));
  }
  if (q) {
    WEAVER_RETURN_IF_ERROR(write_element_data(job, out, boundary, "qp", 4));
    WEAVER_RETURN_IF_ERROR(write_element_data(job, out, boundary, "qs", 5));
  }
  job.result->elements = elements;
  return finish_text(job, out, file);
}

}  // namespace weaver
