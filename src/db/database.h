// A weaver database: a directory holding one B+tree file per table and a
// MANIFEST naming the committed file of each table.
//
//   DB/MANIFEST        "weaver-db 1" / "table <name> <file>" lines /
//                      "checksum <hex>" over the lines above
//   DB/LOCK            flock()ed by the one writer
//   DB/<name>-<n>.bt   table files; only those the manifest names are live
//
// A writer builds new table files beside the live ones and commits them by
// writing MANIFEST.tmp, syncing it, renaming it over MANIFEST and syncing the
// directory.  A crash before the rename leaves the old state; files no
// manifest names are leftovers, removed by the next writer.
//
// A reader opens every live table file when it opens the database, so it
// reads one committed state (a snapshot) however many commits and file
// deletions writers make meanwhile.
#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "schema/status.h"
#include "storage/btree.h"

namespace weaver {

class Database {
 public:
  enum class Mode { kRead, kWrite };

  // Opens DB.  kWrite takes the writer lock (Busy if another writer holds
  // it) and creates the directory when create_if_missing.
  static Status open(const std::string& dir, Mode mode, bool create_if_missing,
                     std::unique_ptr<Database>* out);
  ~Database();

  bool has_table(const std::string& name) const { return tables_.count(name) != 0; }
  std::vector<std::string> table_names() const;
  std::string table_path(const std::string& name) const;
  // Opens a committed table read-only.
  Status open_table(const std::string& name, uint64_t pool_bytes,
                    std::unique_ptr<BTree>* out) const;

  // Writer only: creates a new, uncommitted file for table `name`.
  Status create_table(const std::string& name, const TableOptions& options, uint64_t pool_bytes,
                      std::unique_ptr<BTree>* out, std::string* file_name);
  // Writer only: makes the given files (already committed with BTree::commit)
  // the live tables, atomically, and deletes the files they replace.
  Status commit(const std::map<std::string, std::string>& table_files);
  // Writer only: deletes an uncommitted file after a failed build.
  void abandon(const std::string& file_name);
  // Writer only: ends the build of table `name` in `file`.  If `built` is OK,
  // commits the table and makes it live; otherwise (or if that fails) closes
  // and deletes the file.  Returns the first error.
  Status publish(const std::string& name, const std::string& file,
                 std::unique_ptr<BTree>& table, Status built);

  // Files in the directory that no manifest names (left by a crashed writer);
  // a writer removes them when it opens.
  const std::vector<std::string>& cleaned_leftovers() const { return cleaned_; }
  const std::string& dir() const { return dir_; }

 private:
  Database(std::string dir, Mode mode) : dir_(std::move(dir)), mode_(mode) {}
  Status read_manifest();
  Status write_manifest(const std::map<std::string, std::string>& tables);
  Status remove_leftovers();

  std::string dir_;
  Mode mode_;
  int lock_fd_ = -1;
  uint64_t next_file_number_ = 1;
  std::map<std::string, std::string> tables_;  // name -> file name
  std::map<std::string, int> snapshot_fds_;    // reader: name -> open descriptor
  Status open_snapshot();
  std::vector<std::string> cleaned_;
};

}  // namespace weaver
