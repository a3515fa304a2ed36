// raw --parts N: what each MPI rank of a solver reads.  A directory OUT with
//   parts.json          the part count, the method, and each part's directory
//   part-00000/ ...     a raw export (mesh.json, mesh.bin) of one part: its
//                       elements, the nodes they use and the anchors of those
//                       that dangle, in local numbering with node_global_id and
//                       element_global_id, every dangling constraint of its
//                       nodes, and shared_nodes / shared_parts: the (local node,
//                       other part) pairs of the nodes other parts also use
// The parts are those of export_parts (writers.h).
#include <sys/stat.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
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

Status write_parts(ExportJob& job, const std::string& tmp) {
  PartMap map;
  std::vector<PartRun> ranges;
  std::string method;
  WEAVER_RETURN_IF_ERROR(export_parts(job, &map, &ranges, &method));
  SharedNodes shared;
  WEAVER_RETURN_IF_ERROR(shared.build(job.mesh, map, tmp + "/scratch", job.scratch_bytes));
  job.plan(job.mesh.node_count() + job.mesh.element_count());
  for (uint32_t p = 0; p < job.options.parts; ++p) {
    Selection s = part_selection(job, map, ranges, p);
    const std::string dir = tmp + "/" + part_dir(p);
    if (::mkdir(dir.c_str(), 0755) != 0) {
      return Status::IOError("cannot create directory " + dir + ": " + std::strerror(errno));
    }
    WEAVER_RETURN_IF_ERROR(job.select(s, true, dir + "/scratch"));
    WEAVER_RETURN_IF_ERROR(write_raw_files(job, dir, &shared));
  }
  const std::string text = parts_json(job, method);
  OutputFile f(tmp + "/parts.json");
  WEAVER_RETURN_IF_ERROR(f.open());
  WEAVER_RETURN_IF_ERROR(f.write_at(0, text.data(), text.size()));
  return f.finish();
}

}  // namespace

Status write_raw_parts(ExportJob& job) {
  if (job.options.parts > job.mesh.element_count()) {
    return Status::InvalidArgument(std::to_string(job.options.parts) + " parts for " +
                                   std::to_string(job.mesh.element_count()) + " elements");
  }
  std::string tmp;
  WEAVER_RETURN_IF_ERROR(start_export_dir(job.options.out, &tmp));
  return finish_export_dir(job, tmp, job.options.out, write_parts(job, tmp));
}

}  // namespace weaver
