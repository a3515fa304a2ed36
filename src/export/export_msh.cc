// msh: Gmsh's MSH 4.1, ASCII.  One node block and one element block (entity
// 3 of dimension 3, no $Entities section), hexahedra (type 5) in Gmsh's
// corner order, then one $ElementData view per field: level, and vp, vs, rho
// when the mesh has material (and qp, qs when it has them).  Tags are 1-based positions: id + 1 for
// the whole mesh, the local id + 1 with --box.  Coordinates in metres by default, or ticks. Written
// in one sequential stream: a pass over the nodes for their tags, one for their coordinates, one
// over the elements for their corners, and one a field.
#include <string>

#include "export/writers.h"

namespace weaver {
namespace {

constexpr int kGmshHexahedron = 5;

// "count count 1 count": the first line of $Nodes and $Elements (one block).
std::string block_header(uint64_t count) {
  const std::string c = std::to_string(count);
  return "1 " + c + " 1 " + c + "\n";
}

Status write_nodes(ExportJob& job, Section& out) {
  const uint64_t n = job.node_count();
  WEAVER_RETURN_IF_ERROR(
      out.text("$Nodes\n" + block_header(n) + "3 1 0 " + std::to_string(n) + "\n"));
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
  return out.text("$EndNodes\n");
}

Status write_elements(ExportJob& job, Section& out) {
  const uint64_t e = job.element_count();
  WEAVER_RETURN_IF_ERROR(out.text("$Elements\n" + block_header(e) + "3 1 " +
                                  std::to_string(kGmshHexahedron) + " " + std::to_string(e) +
                                  "\n"));
  LineBuffer line;
  uint64_t tag = 0;
  WEAVER_RETURN_IF_ERROR(for_each_element(job, true, [&](const MeshElement& el) {
    line.field(++tag);
    for (int i = 0; i < 8; ++i) line.ch(' '), line.field(el.nodes[kVtkHexCorner[i]] + 1);
    line.ch('\n');
    return line.emit(out);
  }));
  return out.text("$EndElements\n");
}

// One view of element data: field 0 level, 1 vp, 2 vs, 3 rho, 4 qp, 5 qs.
Status write_element_data(ExportJob& job, Section& out, const char* name, int field) {
  WEAVER_RETURN_IF_ERROR(out.text(std::string("$ElementData\n1\n\"") + name +
                                  "\"\n1\n0\n3\n0\n1\n" + std::to_string(job.element_count()) +
                                  "\n"));
  LineBuffer line;
  uint64_t tag = 0;
  WEAVER_RETURN_IF_ERROR(for_each_element(job, false, [&](const MeshElement& el) {
    line.field(++tag), line.ch(' ');
    if (field == 0) {
      line.field(uint64_t{el.octant.level});
    } else {
      const float v[6] = {0, el.vp, el.vs, el.rho, el.qp, el.qs};
      line.field(double(v[field]));
    }
    line.ch('\n');
    return line.emit(out);
  }));
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
  WEAVER_RETURN_IF_ERROR(out.text("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"));
  WEAVER_RETURN_IF_ERROR(write_nodes(job, out));
  WEAVER_RETURN_IF_ERROR(write_elements(job, out));
  const uint64_t elements = job.result->elements;  // the data views count none
  WEAVER_RETURN_IF_ERROR(write_element_data(job, out, "level", 0));
  if (material) {
    WEAVER_RETURN_IF_ERROR(write_element_data(job, out, "vp", 1));
    WEAVER_RETURN_IF_ERROR(write_element_data(job, out, "vs", 2));
    WEAVER_RETURN_IF_ERROR(write_element_data(job, out, "rho", 3));
  }
  if (q) {
    WEAVER_RETURN_IF_ERROR(write_element_data(job, out, "qp", 4));
    WEAVER_RETURN_IF_ERROR(write_element_data(job, out, "qs", 5));
  }
  job.result->elements = elements;
  return finish_text(job, out, file);
}

}  // namespace weaver
