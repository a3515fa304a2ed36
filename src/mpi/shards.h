// What every weaver-mpi stage does at its end, on rank 0: commit the
// ranks' shards of the table it wrote, or fail naming the rank.
#pragma once

#include <string>
#include <vector>

#include "db/database.h"

namespace weaver::mpi {

// shards[r] and errors[r] are rank r's (errors[r] "" when it succeeded).
// Commits the non-empty shards in rank order, or, when any rank failed,
// removes every rank's file and prints "weaver-mpi COMMAND: rank R: ..." for
// the first.  Returns the exit status.
int commit_or_fail(Database& db, const std::string& command, const std::string& table,
                   const std::vector<ShardEntry>& shards, const std::vector<std::string>& errors);

}  // namespace weaver::mpi
