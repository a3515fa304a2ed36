// A weaver database: a directory holding one B+tree file per table and a
// MANIFEST naming the committed file of each table.
//
//   DB/MANIFEST        "weaver-db 1" / "table <name> <file>" lines /
//                      "checksum <hex>" over the lines above
//   DB/LOCK            flock()ed by the one writer
//   DB/<name>-<n>.bt   table files; only those the manifest names are live
//   DB/<name>-<n>.<s>.bt  shard s of a sharded table (below)
//
// A writer builds new table files beside the live ones and commits them by
// writing MANIFEST.tmp, syncing it, renaming it over MANIFEST and syncing the
// directory.  A crash before the rename leaves the old state.  Files no
// valid manifest names that have a writer's own name patterns (table files
// "<name>-<n>.bt", MANIFEST.tmp, "tmp-*" scratch directories) are leftovers,
// removed by the next writer; nothing else is ever removed.  A new database
// gets an empty manifest before any table file, so a directory with table
// files and no manifest is refused (`weaver recover` rebuilds one).
//
// Some tables derive from others (the node table from the octant table): a
// commit that replaces a table drops, in the same manifest, every table
// derived from it that the commit does not also replace.
//
// A reader opens every live table file when it opens the database, so it
// reads one committed state (a snapshot) however many commits and file
// deletions writers make meanwhile.
//
// A sharded table (written by the ranks of weaver-mpi, one shard a rank) is
// an ordered list of B+tree files holding disjoint, increasing key ranges,
// named in the MANIFEST by "shard <name> <file> <first key> <last key>
// <records>" lines in key order.  open_table reads it as one tree
// (BTree::open_sharded): every reader works on it unchanged.  The ranks
// write and sync their shard files first; then one writer, holding the
// lock, commits them all with one manifest (commit_shards), so a rank that
// fails or dies before that leaves the old state, and its files are
// leftovers for the next writer.
#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "db/table_files.h"
#include "schema/status.h"
#include "storage/btree.h"

namespace weaver {

// What `Database::recover` found and did, one line per item.
struct RecoverReport {
  std::vector<std::string> tables;     // "octants from octants-7.bt (1234 records)"
  std::vector<std::string> set_aside;  // "octants-3.bt (why)", renamed <file>.unused
  std::string manifest_set_aside;      // "MANIFEST.damaged" when there was one
};

class Database {
 public:
  enum class Mode { kRead, kWrite };

  // Opens DB.  kWrite takes the writer lock (Busy if another writer holds
  // it) and creates the directory when create_if_missing.
  static Status open(const std::string& dir, Mode mode, bool create_if_missing,
                     std::unique_ptr<Database>* out);
  ~Database();
  // Rebuilds the MANIFEST of a database that lost it (or whose manifest is
  // damaged, which is kept as MANIFEST.damaged) from its table files
  // (src/db/recover.cc).  Refuses a database whose manifest is intact.
  static Status recover(const std::string& dir, RecoverReport* report);

  bool has_table(const std::string& name) const {
    return tables_.count(name) != 0 || staged_.count(name) != 0;
  }
  std::vector<std::string> table_names() const;
  // A table's file; a sharded table's first shard.
  std::string table_path(const std::string& name) const;
  // The shards of a sharded table (empty for a table of one file).
  std::vector<ShardEntry> shards_of(const std::string& name) const;
  // A table's entry as commit_exactly takes it: its file, or a sharded
  // table's files joined by ','.
  std::string table_value(const std::string& name) const {
    const auto it = tables_.find(name);
    return it == tables_.end() ? "" : it->second;
  }
  // Opens a committed table read-only.
  Status open_table(const std::string& name, uint64_t pool_bytes,
                    std::unique_ptr<BTree>* out) const;

  // Writer only: creates a new, uncommitted file for table `name`.
  Status create_table(const std::string& name, const TableOptions& options, uint64_t pool_bytes,
                      std::unique_ptr<BTree>* out, std::string* file_name);
  // Writer only: makes the given files (already committed with BTree::commit)
  // the live tables, atomically, drops the tables derived from those it
  // replaces (saying so on stderr), and deletes the files they replace.
  Status commit(const std::map<std::string, std::string>& table_files);
  // Writer only: a file number for the shards of a new table, which the
  // ranks create with create_shard_table.
  uint64_t reserve_file_number() { return next_file_number_++; }
  // Writer only: makes the given shards (each a committed B+tree file, in
  // key order) table `name`, as commit does.
  Status commit_shards(const std::string& name, const std::vector<ShardEntry>& shards);
  // Writer only: makes exactly these tables live (recovery).
  Status commit_exactly(const std::map<std::string, std::string>& tables);
  // Writer only: deletes an uncommitted file after a failed build (never a
  // file the manifest names).
  void abandon(const std::string& file_name);
  // Writer only: ends the build of table `name` in `file`.  If `built` is OK,
  // commits the table and makes it live; otherwise (or if that fails) closes
  // and deletes the file.  Returns the first error.
  Status publish(const std::string& name, const std::string& file, std::unique_ptr<BTree>& table,
                 Status built);
  // Writer only: ends the build of table `name` in `file` as publish does,
  // but stages it instead of making it live: this Database's open_table
  // serves it from now on, and its next commit (a later publish) makes it
  // live together with that commit's tables, in one manifest.  Staged files
  // never committed are deleted when the Database closes, so a command of
  // several stages (weaver mesh) leaves the old tables or all the new ones.
  Status stage(const std::string& name, const std::string& file, std::unique_ptr<BTree>& table,
               Status built);
  // Stages the given shards (each a committed B+tree file, in key order) as
  // table `name`, as stage does a file: the ranks of weaver-mpi mesh write
  // the octant table's shards, rank 0 stages them, and the node table's
  // commit makes both live.  In a reader (another rank of the same run),
  // open_table serves the staged table, which the manifest does not name
  // yet, and nothing is deleted when the Database closes.
  Status stage_shards(const std::string& name, const std::vector<ShardEntry>& shards);

  // Files in the directory that no manifest names (left by a crashed writer);
  // a writer removes them when it opens.
  const std::vector<std::string>& cleaned_leftovers() const { return cleaned_; }
  // Tables the last commit dropped because a table they derive from changed.
  const std::vector<std::string>& dropped_tables() const { return dropped_; }
  const std::string& dir() const { return dir_; }

 private:
  Database(std::string dir, Mode mode) : dir_(std::move(dir)), mode_(mode) {}
  Status open_existing(bool create_if_missing);
  Status lock();
  Status start_without_manifest(bool create_if_missing, bool check_only);
  Status read_manifest();
  Status write_manifest(const std::map<std::string, std::string>& tables, bool* renamed = nullptr);
  Status remove_leftovers();
  // Forgets a staged table, deleting its files in a writer.
  void unstage(const std::string& name);
  // One table file, through the reader's snapshot when there is one.
  Status open_file(const std::string& file, uint64_t pool_bytes, std::unique_ptr<BTree>* out) const;
  Status open_sharded(const std::string& name, uint64_t pool_bytes,
                      std::unique_ptr<BTree>* out) const;

  std::string dir_;
  Mode mode_;
  int lock_fd_ = -1;
  uint64_t next_file_number_ = 1;
  // name -> file name; a sharded table's shard files joined by ','.
  std::map<std::string, std::string> tables_;
  std::map<std::string, std::string> staged_;      // table -> its staged file (stage)
  std::map<std::string, ShardEntry> shard_files_;  // file -> its shard entry, for the manifest
  std::map<std::string, int> snapshot_fds_;        // reader: file -> open descriptor
  Status open_snapshot();
  std::vector<std::string> cleaned_;
  std::vector<std::string> dropped_;
};

// The table that `name` is computed from ("" for none): the node table is
// extracted from the octant table.
std::string table_source(const std::string& name);
}  // namespace weaver
