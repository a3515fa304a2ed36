#include "mpi/shards.h"

#include <cstdio>

#include "cli/cli.h"

namespace weaver::mpi {

int commit_or_fail(Database& db, const std::string& command, const std::string& table,
                   const std::vector<ShardEntry>& shards, const std::vector<std::string>& errors) {
  std::vector<ShardEntry> kept;
  for (size_t r = 0; r < shards.size(); ++r) {
    if (!errors[r].empty()) {
      for (const ShardEntry& s : shards) std::remove((db.dir() + "/" + s.file).c_str());
      std::fprintf(stderr, "weaver-mpi %s: rank %zu: %s\n", command.c_str(), r, errors[r].c_str());
      return 1;
    }
    if (shards[r].records > 0) kept.push_back(shards[r]);
  }
  const Status st = db.commit_shards(table, kept);
  if (!st.ok()) {
    for (const ShardEntry& s : kept) db.abandon(s.file);
    std::fprintf(stderr, "weaver-mpi %s: rank 0: %s\n", command.c_str(),
                 cli::error_text(st).c_str());
    return 1;
  }
  return 0;
}

}  // namespace weaver::mpi
