// The name of a model database's table (its layout and readers are in
// modeldb/model_table.h): here so that the readers of any database (the
// mesh reader, which opens a model database's cells as an octree) can name
// it without depending on modeldb/.
#pragma once

namespace weaver {

inline constexpr char kModelTable[] = "model";

}  // namespace weaver
