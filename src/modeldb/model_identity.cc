#include "modeldb/model_identity.h"

#include <fcntl.h>
#include <unistd.h>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>

#include "db/database.h"
#include "db/model_table_name.h"
#include "modeldb/model_table.h"
#include "storage/page_format.h"

namespace weaver {
namespace {

// A digest of a table file's pages past its header: each page begins with
// the checksum of the rest of it, so the checksums stand for the contents.
// (The header holds the metadata, whose source path may differ between two
// imports of the same file.)
Status pages_digest(const std::string& path, uint32_t page_size, uint64_t* digest) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return Status::IOError(path + ": " + std::strerror(errno));
  uint64_t h = 0xcbf29ce484222325ULL;
  std::vector<unsigned char> buf(size_t{256} * page_size);
  for (uint64_t offset = page_size;;) {
    const ssize_t got = ::pread(fd, buf.data(), buf.size(), static_cast<off_t>(offset));
    if (got < 0) {
      const int e = errno;
      ::close(fd);
      return Status::IOError(path + ": " + std::strerror(e));
    }
    for (ssize_t at = 0; at + 4 <= got; at += page_size) {
      for (int b = 0; b < 4; ++b) h = (h ^ buf[at + b]) * 0x100000001b3ULL;
    }
    if (static_cast<size_t>(got) < buf.size()) break;
    offset += buf.size();
  }
  ::close(fd);
  *digest = h;
  return Status::Ok();
}

// "etree /data/labase.e" -> "etree:labase.e" (';' would end the metadata item).
std::string source_name(const std::string& source) {
  const size_t space = source.find(' ');
  std::string name = space == std::string::npos
                         ? source
                         : source.substr(0, space) + ":" +
                               std::filesystem::path(source.substr(space + 1)).filename().string();
  for (char& c : name) {
    if (c == ';' || c == '#' || c == '=') c = '_';
  }
  return name.empty() ? "model" : name;
}

}  // namespace

Status model_table_identity(const std::string& db_dir, std::string* identity) {
  std::unique_ptr<Database> db;
  WEAVER_RETURN_IF_ERROR(Database::open(db_dir, Database::Mode::kRead, false, &db));
  if (!db->has_table(kModelTable)) return Status::NotFound(db_dir + " has no model table");
  std::unique_ptr<BTree> table;
  WEAVER_RETURN_IF_ERROR(db->open_table(kModelTable, 1 << 20, &table));
  ModelInfo info;
  model_info_from_metadata(table->options().metadata, &info);
  uint64_t digest = 0;
  WEAVER_RETURN_IF_ERROR(
      pages_digest(db->table_path(kModelTable), table->options().page_size, &digest));
  char hex[20];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(digest));
  *identity = source_name(info.source) + "#" + hex;
  return Status::Ok();
}

bool is_model_identity(const std::string& name) {
  return name.rfind("db:", 0) != 0 && name.find('#') != std::string::npos;
}

std::string find_model_database(const std::string& identity, const std::vector<std::string>& dirs) {
  for (const std::string& dir : dirs) {
    std::string id;
    if (!dir.empty() && model_table_identity(dir, &id).ok() && id == identity) return dir;
  }
  return "";
}

}  // namespace weaver
