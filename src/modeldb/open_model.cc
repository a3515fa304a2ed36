#include "modeldb/open_model.h"

#include "modeldb/db_model.h"

namespace weaver {

Status open_velocity_model(const std::string& name, const std::string& grid_file,
                           MemoryBudget memory, int threads, std::unique_ptr<VelocityModel>* out) {
  if (name.rfind("db:", 0) == 0) {
    std::unique_ptr<DbModel> m;
    WEAVER_RETURN_IF_ERROR(DbModel::open(name.substr(3), memory, threads, &m));
    *out = std::move(m);
    return Status::Ok();
  }
  return make_model(name, grid_file, out);
}

}  // namespace weaver
