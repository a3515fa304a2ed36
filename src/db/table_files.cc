#include "db/table_files.h"

#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

namespace fs = std::filesystem;

namespace weaver {

bool is_table_file_name(const std::string& file) {
  const size_t dash = file.rfind('-');
  if (dash == std::string::npos || dash == 0 || file.size() < dash + 5) return false;
  if (file.compare(file.size() - 3, 3, ".bt") != 0) return false;
  for (size_t i = 0; i < dash; ++i) {
    if (!std::islower(static_cast<unsigned char>(file[i])) && file[i] != '_') return false;
  }
  for (size_t i = dash + 1; i < file.size() - 3; ++i) {
    if (!std::isdigit(static_cast<unsigned char>(file[i]))) return false;
  }
  return true;
}

uint64_t table_file_number(const std::string& file) {
  if (!is_table_file_name(file)) return 0;
  const size_t dash = file.rfind('-');
  try {
    return std::stoull(file.substr(dash + 1, file.size() - 3 - dash - 1));
  } catch (...) {
    return 0;
  }
}

std::string table_file_table(const std::string& file) {
  return is_table_file_name(file) ? file.substr(0, file.rfind('-')) : "";
}

std::string shard_file_name(const std::string& name, uint64_t number, int shard) {
  return name + "-" + std::to_string(number) + "." + std::to_string(shard) + ".bt";
}

bool is_shard_file_name(const std::string& file) {
  // "<name>-<n>.<s>.bt" is a table file name once the ".<s>" is taken out.
  if (file.size() < 8 || file.compare(file.size() - 3, 3, ".bt") != 0) return false;
  const size_t dot = file.rfind('.', file.size() - 4);
  if (dot == std::string::npos || dot + 1 >= file.size() - 3) return false;
  for (size_t i = dot + 1; i < file.size() - 3; ++i) {
    if (!std::isdigit(static_cast<unsigned char>(file[i]))) return false;
  }
  return is_table_file_name(file.substr(0, dot) + ".bt");
}

namespace {

// A shard file without its ".<s>": the name of a table file.
std::string shard_file_unsharded(const std::string& file) {
  return file.substr(0, file.rfind('.', file.size() - 4)) + ".bt";
}

}  // namespace

uint64_t shard_file_number(const std::string& file) {
  return table_file_number(shard_file_unsharded(file));
}

std::string shard_file_table(const std::string& file) {
  return table_file_table(shard_file_unsharded(file));
}

int shard_file_shard(const std::string& file) {
  const size_t dot = file.rfind('.', file.size() - 4);
  return std::atoi(file.substr(dot + 1, file.size() - 3 - dot - 1).c_str());
}

std::vector<std::string> table_value_files(const std::string& value) {
  std::vector<std::string> files;
  size_t from = 0;
  for (size_t comma; (comma = value.find(',', from)) != std::string::npos; from = comma + 1) {
    files.push_back(value.substr(from, comma - from));
  }
  files.push_back(value.substr(from));
  return files;
}

ShardPlace shard_place_among(const std::vector<bool>& writes, int rank) {
  ShardPlace place{0, 0};
  for (size_t s = 0; s < writes.size(); ++s) {
    place.k += writes[s] && static_cast<int>(s) < rank;
    place.of += writes[s];
  }
  return place;
}

ShardPlace shard_place_among(const std::vector<uint64_t>& begin, int rank) {
  std::vector<bool> writes;
  for (size_t s = 0; s + 1 < begin.size(); ++s) writes.push_back(begin[s] < begin[s + 1]);
  return shard_place_among(writes, rank);
}

std::string without_shard_place(const std::string& metadata) {
  const size_t at = metadata.find(";shard=");
  if (at == std::string::npos) return metadata;
  const size_t end = metadata.find(';', at + 1);
  return metadata.substr(0, at) + (end == std::string::npos ? "" : metadata.substr(end));
}

std::string with_shard_place(const std::string& metadata, ShardPlace place) {
  return without_shard_place(metadata) + ";shard=" + std::to_string(place.k) + "/" +
         std::to_string(place.of);
}

bool shard_place_of(const std::string& metadata, ShardPlace* place) {
  const size_t at = metadata.find(";shard=");
  if (at == std::string::npos) return false;
  int k = -1, of = -1, used = 0;
  const std::string item = metadata.substr(at + 7, metadata.find(';', at + 1) - at - 7);
  if (std::sscanf(item.c_str(), "%d/%d%n", &k, &of, &used) != 2 ||
      used != static_cast<int>(item.size()) || k < 0 || k >= of) {
    return false;
  }
  *place = ShardPlace{k, of};
  return true;
}

Status finish_shard(const std::string& dir, std::unique_ptr<BTree>& table, Status built,
                    ShardPlace place, ShardEntry* entry, uint64_t* bytes) {
  const std::string path = dir + "/" + entry->file;
  table->set_metadata(with_shard_place(table->options().metadata, place));
  if (built.ok()) built = table->commit();
  if (built.ok() && table->size() > 0) {
    entry->records = table->size();
    built = table->select(0, &entry->first_key, nullptr);
    if (built.ok()) built = table->select(table->size() - 1, &entry->last_key, nullptr);
  }
  *bytes = built.ok() && entry->records > 0 ? table->file_bytes() : 0;
  table.reset();
  if (!built.ok() || entry->records == 0) {
    entry->records = 0;
    std::remove(path.c_str());
  }
  return built;
}

Status create_shard_table(const std::string& dir, const std::string& file,
                          const TableOptions& options, uint64_t pool_bytes,
                          std::unique_ptr<BTree>* out) {
  std::unique_ptr<File> f;
  WEAVER_RETURN_IF_ERROR(open_posix_file(dir + "/" + file, OpenMode::kCreateTruncate, &f));
  return BTree::create(std::move(f), options, pool_bytes, out);
}

bool is_database_dir(const std::string& dir) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return false;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    if (is_table_file_name(name) || is_shard_file_name(name)) return true;
    if (name != kManifestFile) continue;
    char head[sizeof kManifestHeader] = {};
    std::FILE* f = std::fopen(entry.path().c_str(), "rb");
    const size_t got = f != nullptr ? std::fread(head, 1, sizeof head - 1, f) : 0;
    if (f != nullptr) std::fclose(f);
    if (got == sizeof head - 1 && std::string(head) == kManifestHeader) return true;
  }
  return false;
}

}  // namespace weaver
