#include "export/export.h"

#include <memory>

#include "export/writers.h"

namespace weaver {

bool export_format_from_name(const std::string& name, ExportFormat* out) {
  static const std::pair<const char*, ExportFormat> kNames[] = {
      {"csv", ExportFormat::kCsv},
      {"vtu", ExportFormat::kVtu},
      {"msh", ExportFormat::kMsh},
      {"metis", ExportFormat::kMetis},
      {"metis-mesh", ExportFormat::kMetisMesh},
      {"raw", ExportFormat::kRaw}};
  for (const auto& [n, f] : kNames) {
    if (name == n) return *out = f, true;
  }
  return false;
}

ExportMemory::ExportMemory(MemoryBudget budget) : plan(budget) {
  // Every element looks up its 8 corners and every dangling node its
  // anchors: the larger the node pool, the fewer of those go to disk.
  node_pool = plan.take("node table pool", 1, 2);
  // The leaves are read once, in order; metis also looks up the leaves
  // across each face, which lie near in Z-order.
  octant_pool = plan.take("octant table pool", 1, 8, 16ull << 20);
  // Up to 12 sections of a binary file, each buffering its array's writes.
  buffers = plan.take("output buffers", 1, 8, 12ull << 20);
}

Status finish_text(ExportJob& job, Section& out, OutputFile& file) {
  WEAVER_RETURN_IF_ERROR(out.flush());
  job.result->bytes += out.end();
  return file.finish();
}

Status write_element_lines(ExportJob& job, const std::string& path, const std::string& head,
                           bool with_nodes,
                           const std::function<void(const MeshElement&, LineBuffer&)>& line_of) {
  OutputFile file(path);
  WEAVER_RETURN_IF_ERROR(file.open());
  Section out(file, 0, job.section_buffer * 4);
  WEAVER_RETURN_IF_ERROR(out.text(head));
  LineBuffer line;
  ElementScan scan;
  WEAVER_RETURN_IF_ERROR(scan.start(job.mesh, 0, with_nodes));
  for (; scan.valid(); scan.next()) {
    line_of(scan.element(), line);
    line.ch('\n');
    WEAVER_RETURN_IF_ERROR(line.emit(out));
    ++job.result->elements;
    job.tick();
  }
  WEAVER_RETURN_IF_ERROR(scan.status());
  return finish_text(job, out, file);
}

Status export_mesh(const std::string& db_dir, const ExportOptions& options, ExportResult* result) {
  *result = ExportResult{};
  const ExportMemory memory(options.memory);
  std::unique_ptr<Mesh> mesh;
  WEAVER_RETURN_IF_ERROR(Mesh::open(db_dir, memory.octant_pool, memory.node_pool, &mesh));
  ExportJob job{*mesh, options, std::max<size_t>(memory.buffers / 12, 4096), result};
  switch (options.format) {
    case ExportFormat::kCsv: return write_csv(job);
    case ExportFormat::kVtu: return write_vtu(job);
    case ExportFormat::kMsh: return write_msh(job);
    case ExportFormat::kMetis: return write_metis_graph(job);
    case ExportFormat::kMetisMesh: return write_metis_mesh(job);
    case ExportFormat::kRaw: return write_raw(job);
  }
  return Status::InvalidArgument("unknown export format");
}

}  // namespace weaver
