// The guard every writer of a user-named file passes first: an output path
// must not be a weaver database, nor lie inside one (a typo in `--out`
// such as DB/MANIFEST or DB/octants-2.bt would otherwise replace a table).
#pragma once

#include <string>

#include "schema/status.h"

namespace weaver {

// InvalidArgument naming the database when path is a database directory or
// lies inside one (symbolic links and ".." followed); OK otherwise.  Looks
// only: nothing is created.
Status check_output_path(const std::string& path);

}  // namespace weaver
