// The files of a database's tables, and the shards of a sharded table: their
// names ("<name>-<n>.bt", "<name>-<n>.<s>.bt"), a shard's place among its
// table's, and building a shard file outside a Database object (a rank of
// weaver-mpi).  Database (db/database.h) names and commits them; `weaver
// recover` and the output-path guard read their names.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "schema/status.h"
#include "storage/btree.h"

namespace weaver {

// The manifest's file name and its first line (do not change: on disk).
inline constexpr char kManifestFile[] = "MANIFEST";
inline constexpr char kManifestHeader[] = "weaver-db 1";

// One shard of a sharded table, as the MANIFEST names it.
struct ShardEntry {
  std::string file;
  uint64_t first_key = 0, last_key = 0, records = 0;
};

// Whether a directory entry has the name of a table file, "<name>-<n>.bt".
bool is_table_file_name(const std::string& file);
// The <n> of "<name>-<n>.bt" (0 if none) and the <name>.
uint64_t table_file_number(const std::string& file);
std::string table_file_table(const std::string& file);
// "<name>-<n>.<shard>.bt", shard `shard` of table file number n, and whether
// a directory entry has that form.
std::string shard_file_name(const std::string& name, uint64_t number, int shard);
bool is_shard_file_name(const std::string& file);
// A shard file's <n>, <shard> and <name>.  REQUIRES: is_shard_file_name.
uint64_t shard_file_number(const std::string& file);
int shard_file_shard(const std::string& file);
std::string shard_file_table(const std::string& file);
// The files of a tables_ value: one, or a sharded table's shards.
std::vector<std::string> table_value_files(const std::string& value);
// A shard file's place among its table's: the k-th of K files (the ranks
// that write none not counted), kept in its metadata (";shard=k/K") so that
// `weaver recover` can tell a whole set of shards from one that lost a file.
// A sharded table's readers, and so `weaver compact`, do not see the item.
struct ShardPlace {
  int k = 0, of = 1;
};
// The place of rank `rank` among the ranks that write a file (writes[s]),
// and among the ranks whose runs [begin[s], begin[s+1]) are not empty
// (begin has an entry past the last rank's).
ShardPlace shard_place_among(const std::vector<bool>& writes, int rank);
ShardPlace shard_place_among(const std::vector<uint64_t>& begin, int rank);
std::string with_shard_place(const std::string& metadata, ShardPlace place);
std::string without_shard_place(const std::string& metadata);
// False when the metadata has no well-formed place.
bool shard_place_of(const std::string& metadata, ShardPlace* place);
// Ends the build of a shard file in dir: if `built` is OK, records its place
// in its metadata, commits (syncs) it and describes it in *entry (first and
// last key, records) and *bytes; closes it, and deletes it when it failed or
// holds no record (records 0).  Returns the first error.
Status finish_shard(const std::string& dir, std::unique_ptr<BTree>& table, Status built,
                    ShardPlace place, ShardEntry* entry, uint64_t* bytes);
// Creates shard file `file` in dir outside any Database object: a rank of a
// parallel writer, whose database rank 0 holds open for writing.
Status create_shard_table(const std::string& dir, const std::string& file,
                          const TableOptions& options, uint64_t pool_bytes,
                          std::unique_ptr<BTree>* out);

// Whether dir is a weaver database: it holds a MANIFEST starting with
// kManifestHeader, or table or shard files.
bool is_database_dir(const std::string& dir);

}  // namespace weaver
