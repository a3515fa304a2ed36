#include "modeldb/open_model.h"

#include "model/rfile_model.h"
#include "modeldb/db_model.h"

namespace weaver {

Status open_velocity_model(const std::string& name, const std::string& grid_file,
                           MemoryBudget memory, int threads, std::unique_ptr<VelocityModel>* out) {
  if (names_model_database(name)) {
    std::unique_ptr<DbModel> m;
    WEAVER_RETURN_IF_ERROR(DbModel::open(model_database_dir(name), memory, threads, &m));
    *out = std::move(m);
    return Status::Ok();
  }
  if (name.rfind("rfile:", 0) == 0) {
    std::unique_ptr<RfileModel> m;
    WEAVER_RETURN_IF_ERROR(RfileModel::open(name.substr(6), memory, threads, &m));
    *out = std::move(m);
    return Status::Ok();
  }
  return make_model(name, grid_file, out);
}

bool is_model_source(const std::string& name) {
  for (const char* kind : {"etree:", "grid:", "layers:", "xyz:"}) {
    if (name.rfind(kind, 0) == 0) return true;
  }
  return false;
}

Status import_model_source(const std::string& db_dir, MemoryBudget memory, std::string* name,
                           ModelImportResult* result) {
  ModelImportOptions o;
  o.from = *name;
  o.memory = memory;
  WEAVER_RETURN_IF_ERROR(import_model(db_dir, o, result));
  *name = "db:" + db_dir;
  return Status::Ok();
}

}  // namespace weaver
