#include "db/database.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "db/aggregate_table.h"
#include "db/boundary_table.h"
#include "db/node_table.h"
#include "db/octant_table.h"
#include "db/partition_table.h"
#include "storage/file.h"
#include "storage/manifest_file.h"

namespace fs = std::filesystem;

namespace weaver {
namespace {

constexpr const char* kManifest = kManifestFile;
constexpr char kManifestTmp[] = "MANIFEST.tmp";  // write_manifest_file's temporary
constexpr char kLock[] = "LOCK";

// The entries a new database directory may hold before its first manifest.
bool is_empty_database_dir(const std::string& dir, bool* has_table_files) {
  *has_table_files = false;
  bool empty = true;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    // A crash while the first manifest was written leaves MANIFEST.tmp.
    if (name == kLock || name == kManifestTmp) continue;
    empty = false;
    *has_table_files = *has_table_files || is_table_file_name(name) || is_shard_file_name(name);
  }
  return empty;
}

std::string join(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

}  // namespace

std::string table_source(const std::string& name) {
  return name == kNodeTable || name == kPartitionTable || name == kAggregateTable ||
                 name == kBoundaryTable
             ? kOctantTable
             : "";
}

Database::~Database() {
  while (!staged_.empty()) unstage(staged_.begin()->first);  // never committed: gone
  for (const auto& [name, fd] : snapshot_fds_) ::close(fd);
  if (lock_fd_ >= 0) ::close(lock_fd_);  // releases the flock
}

// Opens the files of the manifest just read.  A writer may commit and delete
// one of them in between: then read the new manifest and try again.
Status Database::open_snapshot() {
  for (int attempt = 0;; ++attempt) {
    bool missing = false;
    std::pair<std::string, std::string> gone;  // the table whose file was missing
    std::string gone_file;
    for (const auto& [name, value] : tables_) {
      for (const std::string& file : table_value_files(value)) {
        const std::string path = dir_ + "/" + file;
        const int fd = open_for_reading(path);
        if (fd < 0 && errno == ENOENT) {
          missing = true;
          gone = {name, value};
          gone_file = file;
          break;
        }
        if (fd < 0) return Status::IOError("cannot open " + path + ": " + std::strerror(errno));
        snapshot_fds_[file] = fd;
      }
      if (missing) break;
    }
    if (!missing) return Status::Ok();
    for (const auto& [name, fd] : snapshot_fds_) ::close(fd);
    snapshot_fds_.clear();
    if (attempt == 100) return Status::Busy(dir_ + ": tables keep changing under the reader");
    tables_.clear();
    WEAVER_RETURN_IF_ERROR(read_manifest());
    // Still named by the newest manifest: deleted, not replaced by a writer.
    const auto now = tables_.find(gone.first);
    if (now != tables_.end() && now->second == gone.second) {
      return Status::Corruption(dir_ + ": the file " + gone_file + " of table '" + gone.first +
                                "' is missing (named by MANIFEST)");
    }
  }
}

Status Database::open(const std::string& dir, Mode mode, bool create_if_missing,
                      std::unique_ptr<Database>* out) {
  std::error_code ec;
  bool created = false;
  if (!fs::is_directory(dir, ec)) {
    if (fs::exists(dir, ec)) return Status::InvalidArgument(dir + ": not a directory");
    if (mode != Mode::kWrite || !create_if_missing) {
      return Status::NotFound(dir + ": no such database directory");
    }
    fs::create_directories(dir, ec);
    if (ec) return Status::IOError("cannot create " + dir + ": " + ec.message());
    created = true;
  }
  std::unique_ptr<Database> db(new Database(dir, mode));
  const Status st = db->open_existing(create_if_missing);
  if (!st.ok()) {
    db.reset();
    if (created) fs::remove_all(dir, ec);  // a failed open leaves no trace
    return st;
  }
  *out = std::move(db);
  return Status::Ok();
}

Status Database::open_existing(bool create_if_missing) {
  // Checked before the lock too, so that a directory that is not a database
  // does not even get a LOCK file.
  if (!fs::exists(dir_ + "/" + kManifest))
    WEAVER_RETURN_IF_ERROR(start_without_manifest(false, true));
  if (mode_ == Mode::kWrite) WEAVER_RETURN_IF_ERROR(lock());
  if (fs::exists(dir_ + "/" + kManifest)) {
    WEAVER_RETURN_IF_ERROR(read_manifest());
  } else {
    WEAVER_RETURN_IF_ERROR(start_without_manifest(create_if_missing, false));
  }
  if (mode_ == Mode::kRead) return open_snapshot();
  WEAVER_RETURN_IF_ERROR(remove_leftovers());
  if (!cleaned_.empty()) {
    std::fprintf(stderr, "weaver: %s: removed %zu file%s left by an interrupted writer: %s\n",
                 dir_.c_str(), cleaned_.size(), cleaned_.size() == 1 ? "" : "s",
                 join(cleaned_).c_str());
  }
  return Status::Ok();
}

Status Database::lock() {
  const std::string lock = dir_ + "/" + kLock;
  lock_fd_ = ::open(lock.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (lock_fd_ < 0) return Status::IOError("cannot open " + lock + ": " + std::strerror(errno));
  if (::flock(lock_fd_, LOCK_EX | LOCK_NB) != 0) {
    return Status::Busy(dir_ + ": another weaver process is writing this database");
  }
  return Status::Ok();
}

// No MANIFEST.  Only an empty directory becomes a database (a writer's, with
// create_if_missing): it gets an empty manifest before any table file, so
// table files without a manifest are never a writer's leftovers but a
// damaged database, which nothing here may delete.
Status Database::start_without_manifest(bool create_if_missing, bool check_only) {
  bool has_tables = false;
  const bool empty = is_empty_database_dir(dir_, &has_tables);
  if (has_tables) {
    return Status::Corruption(dir_ + ": table files but no MANIFEST; 'weaver recover " + dir_ +
                              "' rebuilds it from the tables");
  }
  if (check_only && (empty && mode_ == Mode::kWrite)) return Status::Ok();
  if (mode_ == Mode::kRead || !create_if_missing || !empty) {
    return Status::NotFound(dir_ + ": not a weaver database (no MANIFEST)");
  }
  std::error_code ec;
  if (fs::remove(dir_ + "/" + kManifestTmp, ec)) cleaned_.push_back(kManifestTmp);
  return write_manifest({});
}

Status Database::read_manifest() {
  const std::string path = dir_ + "/" + kManifest;
  std::vector<std::string> lines;
  WEAVER_RETURN_IF_ERROR(read_manifest_file(path, kManifestHeader, &lines));
  for (const std::string& line : lines) {
    std::istringstream fields(line);
    std::string kind, a, b;
    fields >> kind >> a >> b;
    if (kind == "shard" && !a.empty() && is_shard_file_name(b)) {
      ShardEntry e{b};
      if (!(fields >> e.first_key >> e.last_key >> e.records) || e.records == 0 ||
          e.first_key > e.last_key) {
        return Status::Corruption(path + ": bad line '" + line + "'");
      }
      auto it = tables_.find(a);
      if (it != tables_.end() && !shard_files_.count(table_value_files(it->second).back())) {
        return Status::Corruption(path + ": table '" + a + "' is named twice");
      }
      if (it != tables_.end() &&
          shard_files_[table_value_files(it->second).back()].last_key >= e.first_key) {
        return Status::Corruption(path + ": the shards of table '" + a + "' are out of order");
      }
      tables_[a] += (it == tables_.end() ? "" : ",") + b;
      shard_files_[b] = e;
      next_file_number_ = std::max(next_file_number_, shard_file_number(b) + 1);
      continue;
    }
    if (kind != "table" || a.empty() || b.empty() || tables_.count(a)) {
      return Status::Corruption(path + ": bad line '" + line + "'");
    }
    tables_[a] = b;
    next_file_number_ = std::max(next_file_number_, table_file_number(b) + 1);
  }
  return Status::Ok();
}

std::vector<ShardEntry> Database::shards_of(const std::string& name) const {
  std::vector<ShardEntry> out;
  const auto staged = staged_.find(name);
  const auto live = tables_.find(name);
  if (staged == staged_.end() && live == tables_.end()) return out;
  const std::string& value = staged != staged_.end() ? staged->second : live->second;
  for (const std::string& file : table_value_files(value)) {
    const auto e = shard_files_.find(file);
    if (e == shard_files_.end()) return {};
    out.push_back(e->second);
  }
  return out;
}

Status Database::write_manifest(const std::map<std::string, std::string>& tables, bool* renamed) {
  std::vector<std::string> lines;
  for (const auto& [name, value] : tables) {
    const std::vector<std::string> files = table_value_files(value);
    if (files.size() == 1 && !shard_files_.count(files[0])) {
      lines.push_back("table " + name + " " + value);
      continue;
    }
    for (const std::string& f : files) {
      const ShardEntry& e = shard_files_.at(f);
      lines.push_back("shard " + name + " " + f + " " + std::to_string(e.first_key) + " " +
                      std::to_string(e.last_key) + " " + std::to_string(e.records));
    }
  }
  return write_manifest_file(dir_, kManifest, kManifestHeader, lines, renamed);
}

Status Database::remove_leftovers() {
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir_, ec)) {
    const std::string name = entry.path().filename().string();
    if (name == kManifest || name == kLock) continue;
    bool live = false;
    for (const auto& [table, value] : tables_) {
      for (const std::string& file : table_value_files(value)) live = live || file == name;
    }
    const bool shard = is_shard_file_name(name);
    const bool ours =
        name == kManifestTmp || is_table_file_name(name) || shard || name.rfind("tmp-", 0) == 0;
    if (live || !ours) continue;
    next_file_number_ = std::max(next_file_number_,
                                 (shard ? shard_file_number(name) : table_file_number(name)) + 1);
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
  return it == tables_.end() ? "" : dir_ + "/" + table_value_files(it->second).front();
}

Status Database::open_file(const std::string& file, uint64_t pool_bytes,
                           std::unique_ptr<BTree>* out) const {
  std::unique_ptr<File> f;
  const std::string path = dir_ + "/" + file;
  const auto snap = snapshot_fds_.find(file);
  if (snap != snapshot_fds_.end()) {
    WEAVER_RETURN_IF_ERROR(dup_posix_file(snap->second, path, &f));
  } else {
    WEAVER_RETURN_IF_ERROR(open_posix_file(path, OpenMode::kReadOnly, &f));
  }
  return BTree::open(std::move(f), pool_bytes, out);
}

// Each shard gets an equal part of the pool (a reader mostly works in one
// shard at a time, but a cursor and a lookup may sit in two).
Status Database::open_sharded(const std::string& name, uint64_t pool_bytes,
                              std::unique_ptr<BTree>* out) const {
  const std::vector<ShardEntry> shards = shards_of(name);
  const uint64_t each = std::max<uint64_t>(pool_bytes / shards.size(), 256 << 10);
  std::vector<std::unique_ptr<BTree>> trees;
  std::vector<std::string> metadata;
  for (const ShardEntry& e : shards) {
    std::unique_ptr<BTree> t;
    WEAVER_RETURN_IF_ERROR(open_file(e.file, each, &t));
    if (t->size() != e.records) {
      return Status::Corruption(dir_ + "/" + e.file + ": holds " + std::to_string(t->size()) +
                                " records, MANIFEST says " + std::to_string(e.records));
    }
    metadata.push_back(t->options().metadata);
    trees.push_back(std::move(t));
  }
  WEAVER_RETURN_IF_ERROR(BTree::open_sharded(std::move(trees), out));
  // An octant shard counts its own leaves per level; the other tables'
  // shards carry the table's metadata whole (a node shard, its octree's).
  // Their places are theirs alone.
  for (std::string& m : metadata) m = without_shard_place(m);
  (*out)->set_metadata((*out)->options().key_kind == KeyKind::kOctant
                           ? merge_shard_metadata(metadata)
                           : metadata.front());
  return Status::Ok();
}

Status Database::open_table(const std::string& name, uint64_t pool_bytes,
                            std::unique_ptr<BTree>* out) const {
  if (!has_table(name)) return Status::NotFound(dir_ + ": no table '" + name + "'");
  if (!shards_of(name).empty()) return open_sharded(name, pool_bytes, out);
  if (staged_.count(name)) return open_file(staged_.at(name), pool_bytes, out);
  return open_file(tables_.at(name), pool_bytes, out);
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

Status Database::commit(const std::map<std::string, std::string>& given) {
  std::map<std::string, std::string> table_files = staged_;  // staged tables go live too
  for (const auto& [name, file] : given) table_files[name] = file;
  std::map<std::string, std::string> next = tables_;
  for (const auto& [name, file] : table_files) next[name] = file;
  std::vector<std::string> dropped;
  for (const auto& [name, file] : tables_) {
    const std::string source = table_source(name);
    if (!source.empty() && table_files.count(source) && !table_files.count(name)) {
      next.erase(name);
      dropped.push_back(name);
    }
  }
  WEAVER_RETURN_IF_ERROR(commit_exactly(next));
  staged_.clear();
  dropped_ = dropped;
  for (const std::string& name : dropped) {
    std::fprintf(stderr, "weaver: %s: dropped table '%s', derived from the replaced table '%s'\n",
                 dir_.c_str(), name.c_str(), table_source(name).c_str());
  }
  return Status::Ok();
}

Status Database::commit_shards(const std::string& name, const std::vector<ShardEntry>& shards) {
  if (shards.empty()) return Status::InvalidArgument("table '" + name + "' has no shard");
  std::string value;
  for (const ShardEntry& e : shards) {
    shard_files_[e.file] = e;
    value += (value.empty() ? "" : ",") + e.file;
  }
  return commit({{name, value}});
}

Status Database::commit_exactly(const std::map<std::string, std::string>& tables) {
  if (mode_ != Mode::kWrite) return Status::InvalidArgument(dir_ + ": opened read-only");
  std::set<std::string> kept;
  for (const auto& [name, value] : tables) {
    for (const std::string& f : table_value_files(value)) kept.insert(f);
  }
  std::vector<std::string> replaced;
  for (const auto& [name, value] : tables_) {
    for (const std::string& f : table_value_files(value)) {
      if (!kept.count(f)) replaced.push_back(f);
    }
  }
  WEAVER_RETURN_IF_ERROR(sync_path(dir_, true));  // the new files' directory entries
  bool renamed = false;
  const Status st = write_manifest(tables, &renamed);
  if (renamed) tables_ = tables;  // readers see the new manifest, error or not
  // Not known to be durable: a power cut may bring the old manifest back, so
  // its files stay until the next writer finds them unnamed.
  if (!st.ok()) return st;
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

Status Database::stage(const std::string& name, const std::string& file,
                       std::unique_ptr<BTree>& table, Status built) {
  if (built.ok()) built = table->commit();
  if (!built.ok()) {
    table.reset();
    abandon(file);
    return built;
  }
  unstage(name);
  staged_[name] = file;
  return Status::Ok();
}

Status Database::stage_shards(const std::string& name, const std::vector<ShardEntry>& shards) {
  if (shards.empty()) return Status::InvalidArgument("table '" + name + "' has no shard");
  unstage(name);
  std::string value;
  for (const ShardEntry& e : shards) {
    shard_files_[e.file] = e;
    value += (value.empty() ? "" : ",") + e.file;
  }
  staged_[name] = value;
  return Status::Ok();
}

void Database::unstage(const std::string& name) {
  const auto it = staged_.find(name);
  if (it == staged_.end()) return;
  if (mode_ == Mode::kWrite) {
    for (const std::string& file : table_value_files(it->second)) abandon(file);
  }
  staged_.erase(it);
}

void Database::abandon(const std::string& file_name) {
  for (const auto& [name, value] : tables_) {
    for (const std::string& file : table_value_files(value)) {
      if (file == file_name) return;  // live after all (a commit failed after its rename)
    }
  }
  std::error_code ec;
  fs::remove(dir_ + "/" + file_name, ec);
}

}  // namespace weaver
