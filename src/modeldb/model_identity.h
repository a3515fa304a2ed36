// A model database named by what it holds, not where it lies: the kind and
// file name of its source and a digest of its model table's pages
// ("etree:labase.e#6f1c0a9d3e22b781").  The octant table's metadata names
// such a model so; the same model gives the same bytes in any directory,
// and a moved database names nothing that is gone.
#pragma once

#include <string>
#include <vector>

#include "schema/status.h"

namespace weaver {

// The identity of db_dir's model table.  NotFound if it has none.
Status model_table_identity(const std::string& db_dir, std::string* identity);

// Whether a metadata `model=` value is such an identity (not a built-in
// model's name, an "rfile:PATH" or an older build's "db:PATH").
bool is_model_identity(const std::string& name);

// The first of `dirs` whose model table has `identity` (empty if none).
std::string find_model_database(const std::string& identity, const std::vector<std::string>& dirs);

}  // namespace weaver
