// The velocity model a command names: "db:MODEL.db" (a model database,
// modeldb/db_model.h) or one of make_model's (model/velocity_model.h); and
// a model file (etree:, grid:, layers:, xyz:), imported into the database
// being built before it is read from there.
#pragma once

#include <memory>
#include <string>

#include "model/velocity_model.h"
#include "modeldb/model_import.h"
#include "util/memory_budget.h"

namespace weaver {

// Whether `name` names a model database ("db:DIR").
inline bool names_model_database(const std::string& name) { return name.rfind("db:", 0) == 0; }
// The directory a model database's name gives.  REQUIRES: names_model_database(name).
inline std::string model_database_dir(const std::string& name) { return name.substr(3); }

// `memory` bounds what a model read from storage holds, for up to `threads`
// threads asking it at once.
Status open_velocity_model(const std::string& name, const std::string& grid_file,
                           MemoryBudget memory, int threads, std::unique_ptr<VelocityModel>* out);

// Whether `name` is a model file to import ("etree:FILE" and the others
// model_import.h reads).
bool is_model_source(const std::string& name);

// Imports the model file `*name` into db_dir's model table (so the mesh's
// own database answers material queries too) and sets *name to
// "db:" + db_dir.  REQUIRES: is_model_source(*name).
Status import_model_source(const std::string& db_dir, MemoryBudget memory, std::string* name,
                           ModelImportResult* result);

}  // namespace weaver
