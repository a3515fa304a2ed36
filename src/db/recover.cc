// Database::recover: a manifest rebuilt from the table files themselves.
//
// Each "<name>-<n>.bt" file is opened and checked page by page; per table the
// newest file that checks out is chosen, unless the table derives from one
// whose chosen file is newer (file numbers grow with every file a writer
// makes, so a derived table older than its source was computed from an
// earlier version of it).  A sharded table's files ("<name>-<n>.<rank>.bt",
// written by the ranks of one weaver-mpi stage) count as one version of it
// when each checks out and their places (";shard=k/K" in each one's
// metadata) show all K of them there, in key order.  Files not chosen are
// renamed "<file>.unused", out of every writer's reach, for the user to
// inspect or delete.
#include <cstdio>
#include <filesystem>
#include <map>

#include "db/database.h"
#include "db/node_table.h"
#include "db/octant_table.h"
#include "storage/manifest_file.h"

namespace weaver {
namespace {

namespace fs = std::filesystem;

// Opens and checks one table file; the reason it is unusable otherwise.
// *entry gets its records and first and last key, *metadata its metadata.
Status check_table_file(const std::string& path, const std::string& table, ShardEntry* entry,
                        std::string* metadata) {
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
  entry->records = t->size();
  *metadata = t->options().metadata;
  if (t->size() == 0) return Status::Ok();
  WEAVER_RETURN_IF_ERROR(t->select(0, &entry->first_key, nullptr));
  return t->select(t->size() - 1, &entry->last_key, nullptr);
}

// One version of a table: a file, or the shard files of one stage by rank.
struct Version {
  std::string file;                   // one file
  std::map<int, std::string> shards;  // or these, by rank
  std::vector<ShardEntry> entries;    // the shards checked, in rank order
  uint64_t records = 0;
  std::vector<std::string> files() const {  // every file of the version
    if (shards.empty()) return {file};
    std::vector<std::string> out;
    for (const auto& [rank, f] : shards) out.push_back(f);
    return out;
  }
};

// Checks every file of v; for shards, that they are all there (places 0..K-1
// in rank order) and hold increasing keys.  The reason v is unusable
// otherwise.
Status check_version(const std::string& dir, const std::string& table, Version* v) {
  std::string metadata;
  if (v->shards.empty()) {
    ShardEntry e;
    WEAVER_RETURN_IF_ERROR(check_table_file(dir + "/" + v->file, table, &e, &metadata));
    v->records = e.records;
    return Status::Ok();
  }
  int expected = -1;
  for (const auto& [rank, file] : v->shards) {
    ShardEntry e{file};
    WEAVER_RETURN_IF_ERROR(check_table_file(dir + "/" + file, table, &e, &metadata));
    ShardPlace place;
    if (!shard_place_of(metadata, &place)) {
      return Status::Corruption(file + ": no place among its table's shards in its metadata");
    }
    const int k = static_cast<int>(v->entries.size());
    if (place.k != k || (expected >= 0 && place.of != expected)) {
      return Status::Corruption(file + " is shard " + std::to_string(place.k) + " of " +
                                std::to_string(place.of) + ", but " + std::to_string(k) +
                                " of its set are before it: a shard is missing");
    }
    if (e.records == 0 || (k > 0 && v->entries.back().last_key >= e.first_key)) {
      return Status::Corruption(file + ": empty, or its keys overlap the shard before it");
    }
    expected = place.of;
    v->entries.push_back(e);
    v->records += e.records;
  }
  if (static_cast<int>(v->entries.size()) != expected) {
    return Status::Corruption("the set of " + v->shards.begin()->second + " has " +
                              std::to_string(v->entries.size()) + " of its " +
                              std::to_string(expected) + " shards: the last are missing");
  }
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
  // Candidates: every table file and every set of shard files, newest
  // first per table.
  std::map<std::string, std::map<uint64_t, Version>, std::less<>> versions;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    if (is_table_file_name(name))
      versions[table_file_table(name)][table_file_number(name)].file = name;
    if (is_shard_file_name(name)) {
      versions[shard_file_table(name)][shard_file_number(name)].shards[shard_file_shard(name)] =
          name;
    }
  }
  if (ec) return Status::IOError("cannot list " + dir + ": " + ec.message());
  std::map<std::string, std::string> chosen;  // table -> manifest value
  std::map<std::string, uint64_t> chosen_number;
  for (auto& [table, by_number] : versions) {
    for (auto it = by_number.rbegin(); it != by_number.rend(); ++it) {
      Version& v = it->second;
      db->next_file_number_ = std::max(db->next_file_number_, it->first + 1);
      if (!v.file.empty()) {  // one number, one writer: shards beside a file are strays
        for (const auto& [rank, f] : v.shards) {
          report->set_aside.push_back(f + " (a shard beside " + v.file + ", of the same number)");
        }
        v.shards.clear();
      }
      const Status st = check_version(dir, table, &v);
      const std::vector<std::string> files = v.files();
      if (!st.ok() || chosen.count(table)) {
        const std::string why = st.ok() ? "an older version of '" + table + "'" : st.message();
        for (const std::string& f : files) report->set_aside.push_back(f + " (" + why + ")");
        continue;
      }
      std::string value;
      for (const std::string& f : files) value += (value.empty() ? "" : ",") + f;
      for (const ShardEntry& e : v.entries) db->shard_files_[e.file] = e;
      chosen[table] = value;
      chosen_number[table] = it->first;
      report->tables.push_back(
          table + " from " + value + " (" + std::to_string(v.records) + " records" +
          (v.shards.empty() ? "" : ", " + std::to_string(files.size()) + " shards") + ")");
    }
  }
  for (auto it = chosen.begin(); it != chosen.end();) {
    const std::string source = table_source(it->first);
    if (!source.empty() &&
        (!chosen.count(source) || chosen_number[source] > chosen_number[it->first])) {
      for (const std::string& f : table_value_files(it->second)) {
        report->set_aside.push_back(f + " (older than the table '" + source + "' it derives from)");
      }
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
