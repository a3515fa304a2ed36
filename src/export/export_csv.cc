// csv: the flat files of DESIGN.md, rows in id order, coordinates in ticks.
//   nodes.csv     id,x,y,z,kind,a0,a1,a2,a3
//   elements.csv  id,x,y,z,level,n0,n1,n2,n3,n4,n5,n6,n7
#include <sys/stat.h>

#include "export/writers.h"

namespace weaver {
namespace {

Status write_nodes(ExportJob& job, const std::string& path) {
  OutputFile file(path);
  WEAVER_RETURN_IF_ERROR(file.open());
  Section out(file, 0, job.section_buffer * 4);
  WEAVER_RETURN_IF_ERROR(out.text("id,x,y,z,kind,a0,a1,a2,a3\n"));
  LineBuffer line;
  WEAVER_RETURN_IF_ERROR(for_each_node(job, true, [&](const MeshNode& n) {
    line.field(n.id), line.ch(','), line.field(uint64_t{n.c.x}), line.ch(',');
    line.field(uint64_t{n.c.y}), line.ch(','), line.field(uint64_t{n.c.z}), line.ch(',');
    line.text(node_kind_name(n.kind));
    for (int i = 0; i < 4; ++i) {
      line.ch(',');
      if (i < n.anchor_count) line.field(n.anchors[i]);
    }
    line.ch('\n');
    return line.emit(out);
  }));
  return finish_text(job, out, file);
}

Status write_elements(ExportJob& job, const std::string& path) {
  return write_element_lines(
      job, path, "id,x,y,z,level,n0,n1,n2,n3,n4,n5,n6,n7\n", true,
      [](const MeshElement& e, LineBuffer& line) {
        line.field(e.id), line.ch(','), line.field(uint64_t{e.octant.x}), line.ch(',');
        line.field(uint64_t{e.octant.y}), line.ch(','), line.field(uint64_t{e.octant.z});
        line.ch(','), line.field(uint64_t{e.octant.level});
        for (uint64_t id : e.nodes) line.ch(','), line.field(id);
      });
}

}  // namespace

Status write_csv(ExportJob& job) {
  std::string nodes = job.options.nodes_path, elements = job.options.elements_path;
  if (!job.options.out.empty()) {
    if (::mkdir(job.options.out.c_str(), 0755) != 0 && errno != EEXIST) {
      return Status::IOError("cannot create directory " + job.options.out + ": " +
                             std::strerror(errno));
    }
    nodes = job.options.out + "/nodes.csv";
    elements = job.options.out + "/elements.csv";
  }
  job.plan((nodes.empty() ? 0 : job.mesh.node_count()) +
           (elements.empty() ? 0 : job.mesh.element_count()));
  if (!nodes.empty()) WEAVER_RETURN_IF_ERROR(write_nodes(job, nodes));
  if (!elements.empty()) WEAVER_RETURN_IF_ERROR(write_elements(job, elements));
  return Status::Ok();
}

}  // namespace weaver
