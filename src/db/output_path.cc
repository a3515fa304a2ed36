#include "db/output_path.h"

#include <filesystem>

#include "db/table_files.h"

namespace fs = std::filesystem;

namespace weaver {
namespace {

// The database among dir and its ancestors, or "".
std::string database_around(fs::path dir) {
  for (; !dir.empty(); dir = dir.parent_path()) {
    if (is_database_dir(dir.string())) return dir.string();
    if (dir == dir.root_path()) break;
  }
  return "";
}

}  // namespace

Status check_output_path(const std::string& path) {
  std::error_code ec;
  const fs::path given = fs::absolute(path, ec).lexically_normal();
  if (ec) return Status::InvalidArgument(path + ": " + ec.message());
  if (is_database_dir(given.string())) {
    return Status::InvalidArgument(path + " is a weaver database: not an output file");
  }
  // The parents as named and as they really are (a link into a database,
  // or ".." out of one).
  fs::path existing = given.parent_path();
  while (!existing.empty() && !fs::exists(existing, ec) && existing != existing.root_path()) {
    existing = existing.parent_path();
  }
  for (const fs::path& dir : {given.parent_path(), fs::canonical(existing, ec)}) {
    const std::string db = database_around(dir);
    if (!db.empty()) {
      return Status::InvalidArgument(path + " is inside the weaver database " + db +
                                     ": write it elsewhere");
    }
  }
  return Status::Ok();
}

}  // namespace weaver
