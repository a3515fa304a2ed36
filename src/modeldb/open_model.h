// The velocity model a command names: "db:MODEL.db" (a model database,
// modeldb/db_model.h) or one of make_model's (model/velocity_model.h).
#pragma once

#include <memory>
#include <string>

#include "model/velocity_model.h"
#include "util/memory_budget.h"

namespace weaver {

// `memory` bounds what a model read from storage holds, for up to `threads`
// threads asking it at once.
Status open_velocity_model(const std::string& name, const std::string& grid_file,
                           MemoryBudget memory, int threads, std::unique_ptr<VelocityModel>* out);

}  // namespace weaver
