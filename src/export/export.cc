#include "export/export.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <functional>
#include <memory>

#include "export/writers.h"

namespace weaver {

bool export_format_from_name(const std::string& name, ExportFormat* out) {
  static const std::pair<const char*, ExportFormat> kNames[] = {
      {"csv", ExportFormat::kCsv},     {"vtu", ExportFormat::kVtu},
      {"pvtu", ExportFormat::kPvtu},   {"msh", ExportFormat::kMsh},
      {"metis", ExportFormat::kMetis}, {"metis-mesh", ExportFormat::kMetisMesh},
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
  // --box and pieces: the sort of their node ids and the tree they end in.
  scratch = plan.take("selection's node set", 1, 8);
}

Status for_each_node(ExportJob& job, bool with_anchors,
                     const std::function<Status(const MeshNode&)>& fn) {
  if (job.sel.whole()) {  // one sequential scan
    NodeScan scan;
    WEAVER_RETURN_IF_ERROR(scan.start(job.mesh, with_anchors));
    for (; scan.valid(); scan.next()) {
      WEAVER_RETURN_IF_ERROR(fn(scan.node()));
      ++job.result->nodes;
      job.tick();
    }
    return scan.status();
  }
  // The selection's nodes are nearly runs of ids: one cursor walks them.
  LocalNodes& local = *job.local;
  NodeScan scan;
  WEAVER_RETURN_IF_ERROR(local.start());
  if (local.valid()) WEAVER_RETURN_IF_ERROR(scan.start(job.mesh, with_anchors));
  while (local.valid()) {
    WEAVER_RETURN_IF_ERROR(scan.seek(local.global()));
    WEAVER_RETURN_IF_ERROR(fn(scan.node()));
    ++job.result->nodes;
    job.tick();
    WEAVER_RETURN_IF_ERROR(local.next());
  }
  return Status::Ok();
}

Status for_each_element(ExportJob& job, bool with_nodes,
                        const std::function<Status(const MeshElement&)>& fn) {
  return scan_selected(job.mesh, job.sel, with_nodes, [&](MeshElement& e) {
    if (with_nodes) {
      for (uint64_t& id : e.nodes) WEAVER_RETURN_IF_ERROR(job.local->local_id(id, &id));
    }
    WEAVER_RETURN_IF_ERROR(fn(e));
    ++job.result->elements;
    job.tick();
    return Status::Ok();
  });
}

Status export_parts(ExportJob& job, PartMap* map, std::vector<PartRun>* ranges,
                    std::string* method) {
  Mesh& mesh = job.mesh;
  const uint32_t parts = job.options.parts;
  ranges->clear();
  if (mesh.has_partition() && mesh.partition_parts() == parts) {
    *method = mesh.partition_method();
    if (mesh.partition_table().size() != parts) return mesh.partition(map);
    BTreeCursor c;  // one run a part: read them
    WEAVER_RETURN_IF_ERROR(mesh.partition_table().seek_cursor(0, &c));
    while (c.valid()) {
      uint32_t part = 0;
      std::memcpy(&part, c.payload(), 4);
      ranges->push_back({c.key(), part});
      WEAVER_RETURN_IF_ERROR(c.next());
    }
  } else {
    *method = "sfc by count (no stored partition of " + std::to_string(parts) + " parts)";
    for (uint32_t p = 0; p < parts; ++p) ranges->push_back({mesh.element_count() * p / parts, p});
  }
  *map = PartMap::of_runs(*ranges, parts);
  return Status::Ok();
}

Selection part_selection(const ExportJob& job, const PartMap& map,
                         const std::vector<PartRun>& ranges, uint32_t p) {
  Selection s;
  s.part = p;             // (named, for what is written of the part)
  if (!ranges.empty()) {  // one range a part: read only it, and all of it
    s.first = ranges[p].first;
    s.end = p + 1 < ranges.size() ? ranges[p + 1].first : job.mesh.element_count();
  } else {
    s.parts = &map;
  }
  return s;
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
  WEAVER_RETURN_IF_ERROR(for_each_element(job, with_nodes, [&](const MeshElement& e) {
    line_of(e, line);
    line.ch('\n');
    return line.emit(out);
  }));
  return finish_text(job, out, file);
}

Status ExportJob::box_selection(Selection* s) const {
  const double* b = options.box;
  uint32_t lo[3], hi[3];
  for (int a = 0; a < 3; ++a) {
    double l = b[a], h = b[a + 3];
    if (options.units == ExportUnits::kMetres) {
      l = (l - mesh.units().origin_m[a]) / mesh.units().tick_m;
      h = (h - mesh.units().origin_m[a]) / mesh.units().tick_m;
    }
    if (!(l <= h)) return Status::InvalidArgument("--box: x0,y0,z0 must not exceed x1,y1,z1");
    lo[a] = uint32_t(std::clamp(std::floor(l), 0.0, double(kRootEdge)));
    hi[a] = uint32_t(std::clamp(std::ceil(h), 0.0, double(kRootEdge)));
  }
  s->has_box = true;
  s->lo = {lo[0], lo[1], lo[2]};
  s->hi = {hi[0], hi[1], hi[2]};
  return Status::Ok();
}

namespace {

Status check_options(const ExportOptions& options) {
  const ExportFormat f = options.format;
  if (options.has_box &&
      (f == ExportFormat::kCsv || f == ExportFormat::kMetis || f == ExportFormat::kMetisMesh)) {
    return Status::InvalidArgument("--box works with vtu, pvtu, msh and raw");
  }
  if (options.parts < 1) return Status::InvalidArgument("--parts must be at least 1");
  if (options.parts > 1 && f != ExportFormat::kPvtu && f != ExportFormat::kRaw) {
    return Status::InvalidArgument("--parts works with pvtu and raw");
  }
  if (options.parts > 1 && options.has_box && f == ExportFormat::kRaw) {
    return Status::InvalidArgument("raw takes --box or --parts, not both");
  }
  return Status::Ok();
}

// Opens db_dir's mesh and runs fn on a job of the whole of it.
Status with_job(const std::string& db_dir, const ExportOptions& options, ExportResult* result,
                const std::function<Status(ExportJob&)>& fn) {
  *result = ExportResult{};
  WEAVER_RETURN_IF_ERROR(check_options(options));
  const ExportMemory memory(options.memory);
  std::unique_ptr<Mesh> mesh;
  WEAVER_RETURN_IF_ERROR(Mesh::open(db_dir, memory.octant_pool, memory.node_pool, &mesh));
  ExportJob job(*mesh, options, std::max<size_t>(memory.buffers / 12, 4096), memory.scratch,
                result);
  WEAVER_RETURN_IF_ERROR(job.select(Selection{}, false, ""));
  return fn(job);
}

Status check_one_part_format(const ExportOptions& options) {
  if (options.format == ExportFormat::kRaw || options.format == ExportFormat::kPvtu) {
    return check_options(options);
  }
  return Status::InvalidArgument("one part at a time is for raw and pvtu");
}

}  // namespace

Status export_mesh(const std::string& db_dir, const ExportOptions& options, ExportResult* result) {
  return with_job(db_dir, options, result, [](ExportJob& job) {
    switch (job.options.format) {
      case ExportFormat::kCsv: return write_csv(job);
      case ExportFormat::kVtu: return write_vtu(job);
      case ExportFormat::kPvtu: return write_pvtu(job);
      case ExportFormat::kMsh: return write_msh(job);
      case ExportFormat::kMetis: return write_metis_graph(job);
      case ExportFormat::kMetisMesh: return write_metis_mesh(job);
      case ExportFormat::kRaw: return write_raw(job);
    }
    return Status::InvalidArgument("unknown export format");
  });
}

Status export_parts_begin(const ExportOptions& options) {
  WEAVER_RETURN_IF_ERROR(check_one_part_format(options));
  if (options.format == ExportFormat::kPvtu) return start_pvtu_parts(options);
  std::string tmp;
  return start_export_dir(options.out, &tmp);
}

Status export_one_part(const std::string& db_dir, const ExportOptions& options, uint32_t part,
                       ExportResult* result) {
  WEAVER_RETURN_IF_ERROR(check_one_part_format(options));
  if (part >= options.parts) return Status::InvalidArgument("no part " + std::to_string(part));
  return with_job(db_dir, options, result, [part](ExportJob& job) {
    return job.options.format == ExportFormat::kPvtu ? write_pvtu_one_part(job, part)
                                                     : write_raw_one_part(job, part);
  });
}

Status export_parts_end(const std::string& db_dir, const ExportOptions& options, bool written,
                        ExportResult* result) {
  WEAVER_RETURN_IF_ERROR(check_one_part_format(options));
  const Status st = with_job(db_dir, options, result, [written](ExportJob& job) {
    return job.options.format == ExportFormat::kPvtu ? finish_pvtu_parts(job, written)
                                                     : finish_raw_parts(job, written);
  });
  if (!st.ok() && options.format == ExportFormat::kRaw) {  // the mesh did not open
    std::error_code ec;
    std::filesystem::remove_all(options.out + ".tmp", ec);
  }
  return st;
}

}  // namespace weaver
