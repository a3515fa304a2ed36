// What every weaver-mpi stage does at its end, on rank 0: commit the
// ranks' shards of the table it wrote, or fail naming the rank.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "db/database.h"
#include "mpi/comm.h"

namespace weaver::mpi {

// shards[r] and errors[r] are rank r's (errors[r] "" when it succeeded).
// Commits the non-empty shards in rank order, or, when any rank failed,
// removes every rank's file and prints "weaver-mpi COMMAND: rank R: ..." for
// the first.  Returns the exit status.
// Rank 0 opens DB for writing (holding its lock for the whole stage) and
// reserves the shards' file number; every rank learns it.  False on every
// rank (after rank 0's one line) when rank 0 could not.
bool open_writer(const Comm& comm, const char* command, const std::string& dir,
                 std::unique_ptr<Database>* db, uint64_t* number);

// The end of a stage: every rank's shard, error ("" when none), report line
// and count reach rank 0, which prints the lines, commits the shards
// (commit_or_fail) and prints "<command>: <sum> <what> in <s>s on <N>
// ranks".  Returns the exit status, the same on every rank.
// With staged, rank 0 stages the shards rather than commit them, and every
// rank gets them in *staged.
int finish_stage(const Comm& comm, Database* db, const char* command, const std::string& table,
                 const ShardEntry& mine, const std::string& error, const std::string& line,
                 uint64_t count, const char* what, std::chrono::steady_clock::time_point start,
                 std::vector<ShardEntry>* staged = nullptr);

// The writer and file number of a stage: rank 0's writer, opened here
// (*own) or, when the stage goes on from an earlier one's staged table,
// held; false (after one line) when it cannot be opened.
bool stage_writer(const Comm& comm, const char* command, const std::string& dir, Database* held,
                  bool staged, std::unique_ptr<Database>* own, Database** db, uint64_t* number);

// This process's peak resident set, in bytes (getrusage).
uint64_t peak_rss_bytes();

// stage: stage the shards (Database::stage_shards) for a later stage's
// commit to make live, rather than commit them; *kept (when given) gets the
// shards that hold records.
int commit_or_fail(Database& db, const std::string& command, const std::string& table,
                   const std::vector<ShardEntry>& shards, const std::vector<std::string>& errors,
                   bool stage = false, std::vector<ShardEntry>* kept = nullptr);

// A list of shard entries as one text (for a broadcast), and back.
std::string encode_shards(const std::vector<ShardEntry>& shards);
std::vector<ShardEntry> decode_shards(const std::string& text);

}  // namespace weaver::mpi
