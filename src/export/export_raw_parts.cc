// raw --parts N: what each MPI rank of a solver reads.  A directory OUT with
//   parts.json          the part count, the method, and each part's directory
//   part-00000/ ...     a raw export (mesh.json, mesh.bin) of one part: its
//                       elements, the nodes they use and the anchors of those
//                       that dangle, in local numbering with node_global_id and
//                       element_global_id, every dangling constraint of its
//                       nodes, and shared_nodes / shared_parts: the (local node,
//                       other part) pairs of the nodes other parts also use
// The parts are those of export_parts (writers.h).  Written all in one pass
// (write_raw_parts: shared nodes from every element), or one part at a time
// into OUT.tmp made beforehand (write_raw_one_part, finish_raw_parts: a part's
// shared nodes from its own elements), as weaver-mpi export does on its ranks.
#include <sys/stat.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <vector>

#include "export/shared_nodes.h"
#include "export/writers.h"

namespace weaver {
namespace {

std::string part_dir(uint32_t p) {
  char name[32];
  std::snprintf(name, sizeof name, "part-%05u", p);
  return name;
}

std::string parts_json(const ExportJob& job, const std::string& method) {
  std::string s = "{\n  \"format\": \"weaver-raw-parts\",\n  \"version\": 1,\n";
  s += "  \"parts\": " + std::to_string(job.options.parts) + ",\n";
  s += "  \"method\": \"" + method + "\",\n";
  s += "  \"elements\": " + std::to_string(job.mesh.element_count()) + ",\n";
  s += "  \"nodes\": " + std::to_string(job.mesh.node_count()) + ",\n  \"part_dirs\": [";
  for (uint32_t p = 0; p < job.options.parts; ++p) {
    s += (p ? ", \"" : "\"") + part_dir(p) + "\"";
  }
  return s + "]\n}\n";
}

Status write_parts_json(ExportJob& job, const std::string& tmp, const std::string& method) {
  const std::string text = parts_json(job, method);
  OutputFile f(tmp + "/parts.json");
  WEAVER_RETURN_IF_ERROR(f.open());
  WEAVER_RETURN_IF_ERROR(f.write_at(0, text.data(), text.size()));
  return f.finish();
}

// Part p's directory in tmp, its shared nodes in `shared`.
Status write_part(ExportJob& job, const Selection& s, const std::string& tmp, SharedNodes* shared) {
  const std::string dir = tmp + "/" + part_dir(s.part);
  if (::mkdir(dir.c_str(), 0755) != 0) {
    return Status::IOError("cannot create directory " + dir + ": " + std::strerror(errno));
  }
  WEAVER_RETURN_IF_ERROR(job.select(s, true, dir + "/scratch"));
  return write_raw_files(job, dir, shared);
}

Status write_parts(ExportJob& job, const std::string& tmp) {
  Parts parts;
  WEAVER_RETURN_IF_ERROR(export_parts(job, &parts));
  {
    SharedNodes shared;
    WEAVER_RETURN_IF_ERROR(shared.build(job.mesh, parts.map, tmp + "/scratch", job.scratch_bytes));
    job.plan(job.mesh.node_count() + job.mesh.element_count());
    for (uint32_t p = 0; p < job.options.parts; ++p) {
      WEAVER_RETURN_IF_ERROR(write_part(job, part_selection(job, parts, p), tmp, &shared));
    }
  }
  std::error_code ec;  // the sorts' directory, empty now: not part of the output
  std::filesystem::remove_all(tmp + "/scratch", ec);
  return write_parts_json(job, tmp, parts.method);
}

Status check_part_count(const ExportJob& job) {
  if (job.options.parts <= job.mesh.element_count()) return Status::Ok();
  return Status::InvalidArgument(std::to_string(job.options.parts) + " parts for " +
                                 std::to_string(job.mesh.element_count()) + " elements");
}

}  // namespace

Status write_raw_parts(ExportJob& job) {
  WEAVER_RETURN_IF_ERROR(check_part_count(job));
  std::string tmp;
  WEAVER_RETURN_IF_ERROR(start_export_dir(job.options.out, &tmp));
  return finish_export_dir(job, tmp, job.options.out, write_parts(job, tmp));
}

Status write_raw_one_part(ExportJob& job, uint32_t p) {
  WEAVER_RETURN_IF_ERROR(check_part_count(job));
  Parts parts;
  WEAVER_RETURN_IF_ERROR(export_parts(job, &parts));
  const Selection s = part_selection(job, parts, p);
  const std::string tmp = job.options.out + ".tmp";  // made by export_parts_begin
  const std::string scratch = tmp + "/scratch-" + std::to_string(p);
  SharedNodes shared;
  Status st = shared.build_part(job.mesh, parts.map, s, scratch, job.scratch_bytes);
  if (st.ok()) {
    job.plan(job.mesh.node_count() / job.options.parts +
             job.mesh.element_count() / job.options.parts);
    st = write_part(job, s, tmp, &shared);
  }
  std::error_code ec;
  std::filesystem::remove_all(scratch, ec);
  return st;
}

Status finish_raw_parts(ExportJob& job, bool written) {
  const std::string tmp = job.options.out + ".tmp";
  if (!written) {  // the parts written go; the writer of the failed one reports it
    std::error_code ec;
    std::filesystem::remove_all(tmp, ec);
    return Status::Ok();
  }
  Parts parts;
  Status st = export_parts(job, &parts);
  if (st.ok()) st = write_parts_json(job, tmp, parts.method);
  return finish_export_dir(job, tmp, job.options.out, st);
}

}  // namespace weaver
