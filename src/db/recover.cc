// Database::recover: a manifest rebuilt from the table files themselves.
//
// Each "<name>-<n>.bt" file is opened and checked page by page; per table the
// newest file that checks out is chosen, unless the table derives from one
// whose chosen file is newer (file numbers grow with every file a writer
// makes, so a derived table older than its source was computed from an
// earlier version of it).  Files not chosen are renamed "<file>.unused", out
// of every writer's reach, for the user to inspect or delete.  Shard files
// of sharded tables are set aside too: recover does not rebuild those.
#include <cstdio>
#include <filesystem>

#include "db/database.h"
#include "db/node_table.h"
#include "db/octant_table.h"
#include "storage/manifest_file.h"

namespace weaver {
namespace {

namespace fs = std::filesystem;

// Opens and checks one table file; the reason it is unusable otherwise.
Status check_table_file(const std::string& path, const std::string& table, uint64_t* records) {
  std::unique_ptr<File> f;
  WEAVER_RETURN_IF_ERROR(open_posix_file(path, OpenMode::kReadOnly, &f));
  std::unique_ptr<BTree> t;
  WEAVER_RETURN_IF_ERROR(BTree::open(std::move(f), 1 << 20, &t));
  const KeyKind kind = t->options().key_kind;
  if ((table == kOctantTable && kind != KeyKind::kOctant) ||
      (table == kNodeTable && kind != KeyKind::kNode)) {
    return Status::Corruption(path + ": its header's key kind does not fit table '" + table + "'");
  }
  WEAVER_RETURN_IF_ERROR(t->check_invariants());
  *records = t->size();
  return Status::Ok();
}

}  // namespace

Status Database::recover(const std::string& dir, RecoverReport* report) {
  *report = RecoverReport{};
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return Status::NotFound(dir + ": no such database directory");
  std::unique_ptr<Database> db(new Database(dir, Mode::kWrite));
  WEAVER_RETURN_IF_ERROR(db->lock());
  const std::string manifest = dir + "/MANIFEST";
  if (fs::exists(manifest, ec)) {
    if (db->read_manifest().ok()) {
      return Status::InvalidArgument(dir + ": the MANIFEST is intact; nothing to recover");
    }
    report->manifest_set_aside = "MANIFEST.damaged";
    fs::rename(manifest, dir + "/MANIFEST.damaged", ec);
    if (ec) return Status::IOError("cannot rename " + manifest + ": " + ec.message());
    db->tables_.clear();
  }
  // Candidates: every table file, newest first per table.
  std::map<std::string, std::map<uint64_t, std::string>, std::less<>> files;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    if (is_table_file_name(name)) files[table_file_table(name)][table_file_number(name)] = name;
    // Set aside, never deleted: the next writer would remove a shard file
    // no manifest names.
    if (is_shard_file_name(name)) {
      report->set_aside.push_back(
          name +
          " (a shard of a sharded table: recover rebuilds tables of one file "
          "only)");
    }
  }
  if (ec) return Status::IOError("cannot list " + dir + ": " + ec.message());
  std::map<std::string, std::string> chosen;
  std::map<std::string, uint64_t> chosen_number;
  for (const auto& [table, by_number] : files) {
    for (auto it = by_number.rbegin(); it != by_number.rend(); ++it) {
      uint64_t records = 0;
      const Status st = check_table_file(dir + "/" + it->second, table, &records);
      if (!st.ok()) {
        report->set_aside.push_back(it->second + " (" + st.message() + ")");
        continue;
      }
      if (chosen.count(table)) {
        report->set_aside.push_back(it->second + " (an older version of '" + table + "')");
        continue;
      }
      chosen[table] = it->second;
      chosen_number[table] = it->first;
      report->tables.push_back(table + " from " + it->second + " (" + std::to_string(records) +
                               " records)");
      db->next_file_number_ = std::max(db->next_file_number_, it->first + 1);
    }
  }
  for (auto it = chosen.begin(); it != chosen.end();) {
    const std::string source = table_source(it->first);
    if (!source.empty() &&
        (!chosen.count(source) || chosen_number[source] > chosen_number[it->first])) {
      report->set_aside.push_back(it->second + " (older than the table '" + source +
                                  "' it derives from)");
      it = chosen.erase(it);
    } else {
      ++it;
    }
  }
  for (const std::string& aside : report->set_aside) {
    const std::string file = aside.substr(0, aside.find(' '));
    fs::rename(dir + "/" + file, dir + "/" + file + ".unused", ec);
  }
  std::erase_if(report->tables, [&](const std::string& line) {
    return !chosen.count(line.substr(0, line.find(' ')));
  });
  return db->commit_exactly(chosen);
}

}  // namespace weaver
