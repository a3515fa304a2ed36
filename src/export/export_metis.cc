// metis: the element dual graph in METIS's graph format, for gpmetis.  Line
// 1 is "n m" (elements, graph edges); line i + 1 lists the 1-based ids of
// the elements sharing a face with element i, ascending.  Faces across a 2:1
// step count: a coarse element is adjacent to each finer element on its face
// (mesh/face_neighbors.h).  m is known only at the end, so the first line is
// written last, padded with spaces to the width kept for it.
//
// metis-mesh: mpmetis's mesh file: the element count, then each element's 8
// node ids (1-based) on a line.  mpmetis makes its own dual graph from shared
// nodes, which misses the faces of a non-conforming 2:1 mesh: prefer metis.
#include <algorithm>
#include <string>
#include <vector>

#include "export/writers.h"
#include "mesh/face_neighbors.h"

namespace weaver {
namespace {

constexpr size_t kHeaderWidth = 48;  // "n m" of two 20-digit numbers fits

}  // namespace

Status write_metis_graph(ExportJob& job) {
  job.plan(job.mesh.element_count());
  OutputFile file(job.options.out);
  WEAVER_RETURN_IF_ERROR(file.open());
  Section out(file, kHeaderWidth, job.section_buffer * 4);
  LineBuffer line;
  std::vector<FaceNeighbor> around;
  FaceFinder faces(job.mesh.octants());
  std::vector<uint64_t> ids;
  uint64_t degree_sum = 0;
  WEAVER_RETURN_IF_ERROR(for_each_element(job, false, [&](const MeshElement& e) {
    around.clear();
    WEAVER_RETURN_IF_ERROR(faces.find(e.octant, &around));
    ids.clear();
    for (const FaceNeighbor& n : around) ids.push_back(n.id);
    std::sort(ids.begin(), ids.end());
    for (size_t i = 0; i < ids.size(); ++i) {
      if (i > 0) line.ch(' ');
      line.field(ids[i] + 1);
    }
    line.ch('\n');
    degree_sum += ids.size();
    return line.emit(out);
  }));
  WEAVER_RETURN_IF_ERROR(out.flush());
  if (degree_sum % 2 != 0) {
    return Status::Corruption("the face graph is not symmetric (" + std::to_string(degree_sum) +
                              " neighbour entries): run 'weaver verify'");
  }
  job.result->graph_edges = degree_sum / 2;
  std::string head =
      std::to_string(job.mesh.element_count()) + " " + std::to_string(job.result->graph_edges);
  head.resize(kHeaderWidth - 1, ' ');
  head += '\n';
  WEAVER_RETURN_IF_ERROR(file.write_at(0, head.data(), head.size()));
  job.result->bytes += out.end();
  return file.finish();
}

Status write_metis_mesh(ExportJob& job) {
  job.plan(job.mesh.element_count());
  return write_element_lines(job, job.options.out, std::to_string(job.mesh.element_count()) + "\n",
                             true, [](const MeshElement& e, LineBuffer& line) {
                               for (int i = 0; i < 8; ++i) {
                                 if (i > 0) line.ch(' ');
                                 line.field(e.nodes[kVtkHexCorner[i]] + 1);
                               }
                             });
}

}  // namespace weaver
