#include "db/database.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "storage/manifest_file.h"

namespace fs = std::filesystem;

namespace weaver {
namespace {

constexpr char kManifest[] = "MANIFEST";
constexpr char kManifestTmp[] = "MANIFEST.tmp";  // write_manifest_file's temporary
constexpr char kLock[] = "LOCK";
constexpr char kManifestHeader[] = "weaver-db 1";  // do not change: on disk

// "octants-12.bt" -> 12; 0 if the name has no number.
uint64_t file_number(const std::string& file) {
  const size_t dash = file.rfind('-'), dot = file.rfind('.');
  if (dash == std::string::npos || dot == std::string::npos || dot < dash) return 0;
  try {
    return std::stoull(file.substr(dash + 1, dot - dash - 1));
  } catch (...) {
    return 0;
  }
}

}  // namespace

Database::~Database() {
  for (const auto& [name, fd] : snapshot_fds_) ::close(fd);
  if (lock_fd_ >= 0) ::close(lock_fd_);  // releases the flock
}

// Opens the files of the manifest just read.  A writer may commit and delete
// one of them in between: then read the new manifest and try again.
Status Database::open_snapshot() {
  for (int attempt = 0;; ++attempt) {
    bool missing = false;
    for (const auto& [name, file] : tables_) {
      const int fd = ::open(table_path(name).c_str(), O_RDONLY | O_CLOEXEC);
      if (fd < 0 && errno == ENOENT) {
        missing = true;
        break;
      }
      if (fd < 0) return Status::IOError("cannot open " + table_path(name) + ": " + std::strerror(errno));
      snapshot_fds_[name] = fd;
    }
    if (!missing) return Status::Ok();
    for (const auto& [name, fd] : snapshot_fds_) ::close(fd);
    snapshot_fds_.clear();
    if (attempt == 100) return Status::Busy(dir_ + ": tables keep changing under the reader");
    tables_.clear();
    WEAVER_RETURN_IF_ERROR(read_manifest());
  }
}

Status Database::open(const std::string& dir, Mode mode, bool create_if_missing,
                      std::unique_ptr<Database>* out) {
  std::error_code ec;
  const bool exists = fs::is_directory(dir, ec);
  if (!exists) {
    if (mode != Mode::kWrite || !create_if_missing) {
      return Status::NotFound(dir + ": no such database directory");
    }
    fs::create_directories(dir, ec);
    if (ec) return Status::IOError("cannot create " + dir + ": " + ec.message());
  }
  std::unique_ptr<Database> db(new Database(dir, mode));
  if (mode == Mode::kWrite) {
    const std::string lock = dir + "/" + kLock;
    db->lock_fd_ = ::open(lock.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (db->lock_fd_ < 0) return Status::IOError("cannot open " + lock + ": " + std::strerror(errno));
    if (::flock(db->lock_fd_, LOCK_EX | LOCK_NB) != 0) {
      return Status::Busy(dir + ": another weaver process is writing this database");
    }
  }
  if (fs::exists(dir + "/" + kManifest)) {
    WEAVER_RETURN_IF_ERROR(db->read_manifest());
  } else if (mode == Mode::kRead) {
    return Status::NotFound(dir + ": not a weaver database (no MANIFEST)");
  }
  if (mode == Mode::kRead) WEAVER_RETURN_IF_ERROR(db->open_snapshot());
  if (mode == Mode::kWrite) {
    WEAVER_RETURN_IF_ERROR(db->remove_leftovers());
    if (!db->cleaned_.empty()) {
      std::string names;
      for (const std::string& n : db->cleaned_) names += (names.empty() ? "" : ", ") + n;
      std::fprintf(stderr, "weaver: %s: removed %zu file%s left by an interrupted writer: %s\n",
                   dir.c_str(), db->cleaned_.size(), db->cleaned_.size() == 1 ? "" : "s",
                   names.c_str());
    }
  }
  *out = std::move(db);
  return Status::Ok();
}

Status Database::read_manifest() {
  const std::string path = dir_ + "/" + kManifest;
  std::vector<std::string> lines;
  WEAVER_RETURN_IF_ERROR(read_manifest_file(path, kManifestHeader, &lines));
  for (const std::string& line : lines) {
    std::istringstream fields(line);
    std::string kind, a, b;
    fields >> kind >> a >> b;
    if (kind != "table" || a.empty() || b.empty()) {
      return Status::Corruption(path + ": bad line '" + line + "'");
    }
    tables_[a] = b;
    next_file_number_ = std::max(next_file_number_, file_number(b) + 1);
  }
  return Status::Ok();
}

Status Database::write_manifest(const std::map<std::string, std::string>& tables) {
  std::vector<std::string> lines;
  for (const auto& [name, file] : tables) lines.push_back("table " + name + " " + file);
  return write_manifest_file(dir_, kManifest, kManifestHeader, lines);
}

Status Database::remove_leftovers() {
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir_, ec)) {
    const std::string name = entry.path().filename().string();
    if (name == kManifest || name == kLock) continue;
    bool live = false;
    for (const auto& [table, file] : tables_) live = live || file == name;
    const bool ours = name == kManifestTmp || entry.path().extension() == ".bt" ||
                      name.rfind("tmp-", 0) == 0;
    if (live || !ours) continue;
    next_file_number_ = std::max(next_file_number_, file_number(name) + 1);
    fs::remove_all(entry.path(), ec);
    cleaned_.push_back(name);
  }
  if (ec) return Status::IOError("cannot list " + dir_ + ": " + ec.message());
  return Status::Ok();
}

std::vector<std::string> Database::table_names() const {
  std::vector<std::string> names;
  for (const auto& [name, file] : tables_) names.push_back(name);
  return names;
}

std::string Database::table_path(const std::string& name) const {
  auto it = tables_.find(name);
  return it == tables_.end() ? "" : dir_ + "/" + it->second;
}

Status Database::open_table(const std::string& name, uint64_t pool_bytes,
                            std::unique_ptr<BTree>* out) const {
  if (!has_table(name)) return Status::NotFound(dir_ + ": no table '" + name + "'");
  std::unique_ptr<File> f;
  const auto snap = snapshot_fds_.find(name);
  if (snap != snapshot_fds_.end()) {
    WEAVER_RETURN_IF_ERROR(dup_posix_file(snap->second, table_path(name), &f));
  } else {
    WEAVER_RETURN_IF_ERROR(open_posix_file(table_path(name), OpenMode::kReadOnly, &f));
  }
  return BTree::open(std::move(f), pool_bytes, out);
}

Status Database::create_table(const std::string& name, const TableOptions& options,
                              uint64_t pool_bytes, std::unique_ptr<BTree>* out,
                              std::string* file_name) {
  if (mode_ != Mode::kWrite) return Status::InvalidArgument(dir_ + ": opened read-only");
  *file_name = name + "-" + std::to_string(next_file_number_++) + ".bt";
  std::unique_ptr<File> f;
  WEAVER_RETURN_IF_ERROR(open_posix_file(dir_ + "/" + *file_name, OpenMode::kCreateTruncate, &f));
  return BTree::create(std::move(f), options, pool_bytes, out);
}

Status Database::commit(const std::map<std::string, std::string>& table_files) {
  if (mode_ != Mode::kWrite) return Status::InvalidArgument(dir_ + ": opened read-only");
  std::map<std::string, std::string> next = tables_;
  std::vector<std::string> replaced;
  for (const auto& [name, file] : table_files) {
    if (next.count(name)) replaced.push_back(next[name]);
    next[name] = file;
  }
  WEAVER_RETURN_IF_ERROR(sync_path(dir_, true));  // the new files' directory entries
  WEAVER_RETURN_IF_ERROR(write_manifest(next));
  tables_ = std::move(next);
  std::error_code ec;
  for (const std::string& old : replaced) fs::remove(dir_ + "/" + old, ec);
  return Status::Ok();
}

Status Database::publish(const std::string& name, const std::string& file,
                         std::unique_ptr<BTree>& table, Status built) {
  if (built.ok()) built = table->commit();
  if (built.ok()) built = commit({{name, file}});
  if (!built.ok()) {
    table.reset();
    abandon(file);
  }
  return built;
}

void Database::abandon(const std::string& file_name) {
  std::error_code ec;
  fs::remove(dir_ + "/" + file_name, ec);
}

}  // namespace weaver
