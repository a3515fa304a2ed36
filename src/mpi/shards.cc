#include "mpi/shards.h"

#include <sys/resource.h>

#include <cstdio>
#include <sstream>

#include "cli/cli.h"

namespace weaver::mpi {

bool open_writer(const Comm& comm, const char* command, const std::string& dir,
                 std::unique_ptr<Database>* db, uint64_t* number) {
  std::string failed;
  if (comm.rank() == 0) {
    const Status st = Database::open(dir, Database::Mode::kWrite, false, db);
    if (st.ok()) *number = (*db)->reserve_file_number();
    if (!st.ok()) failed = cli::error_text(st);
  }
  if (!comm.all(failed.empty())) {
    if (comm.rank() == 0) std::fprintf(stderr, "weaver-mpi %s: %s\n", command, failed.c_str());
    return false;
  }
  *number = comm.broadcast(*number);
  return true;
}

bool stage_writer(const Comm& comm, const char* command, const std::string& dir, Database* held,
                  bool staged, std::unique_ptr<Database>* own, Database** db, uint64_t* number) {
  if (!staged) {
    if (!open_writer(comm, command, dir, own, number)) return false;
    *db = own->get();
    return true;
  }
  *db = held;  // rank 0's; null on the others
  if (comm.rank() == 0) *number = held->reserve_file_number();
  *number = comm.broadcast(*number);
  return true;
}

int finish_stage(const Comm& comm, Database* db, const char* command, const std::string& table,
                 const ShardEntry& mine, const std::string& error, const std::string& line,
                 uint64_t count, const char* what, std::chrono::steady_clock::time_point start,
                 std::vector<ShardEntry>* staged) {
  std::ostringstream out;
  out << mine.file << ' ' << mine.records << ' ' << mine.first_key << ' ' << mine.last_key << ' '
      << count << '\n'
      << error << '\x1f' << line;
  const std::vector<std::string> all = comm.gather(out.str());
  int code = 0;
  if (comm.rank() == 0) {
    std::vector<ShardEntry> shards;
    std::vector<std::string> errors;
    uint64_t sum = 0;
    for (const std::string& text : all) {
      std::istringstream in(text);
      ShardEntry e;
      uint64_t n = 0;
      in >> e.file >> e.records >> e.first_key >> e.last_key >> n;
      in.ignore(1);
      std::string err, rank_line;
      std::getline(in, err, '\x1f');
      std::getline(in, rank_line, '\0');
      shards.push_back(e);
      errors.push_back(err);
      sum += n;
      std::printf("%s\n", rank_line.c_str());
    }
    code = commit_or_fail(*db, command, table, shards, errors, staged != nullptr, staged);
    const double secs =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (code == 0) {
      std::printf("%s: %llu %s in %.2fs on %d ranks\n", command, (unsigned long long)sum, what,
                  secs, comm.size());
    }
    std::fflush(stdout);
  }
  code = static_cast<int>(comm.broadcast(uint64_t(code)));
  if (staged != nullptr && code == 0)
    *staged = decode_shards(comm.broadcast(encode_shards(*staged)));
  return code;
}

uint64_t peak_rss_bytes() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<uint64_t>(u.ru_maxrss) * 1024;
}

int commit_or_fail(Database& db, const std::string& command, const std::string& table,
                   const std::vector<ShardEntry>& shards, const std::vector<std::string>& errors,
                   bool stage, std::vector<ShardEntry>* kept_out) {
  std::vector<ShardEntry> kept;
  for (size_t r = 0; r < shards.size(); ++r) {
    if (!errors[r].empty()) {
      for (const ShardEntry& s : shards) std::remove((db.dir() + "/" + s.file).c_str());
      std::fprintf(stderr, "weaver-mpi %s: rank %zu: %s\n", command.c_str(), r, errors[r].c_str());
      return 1;
    }
    if (shards[r].records > 0) kept.push_back(shards[r]);
  }
  const Status st = stage ? db.stage_shards(table, kept) : db.commit_shards(table, kept);
  if (st.ok() && kept_out != nullptr) *kept_out = kept;
  if (!st.ok()) {
    for (const ShardEntry& s : kept) db.abandon(s.file);
    std::fprintf(stderr, "weaver-mpi %s: rank 0: %s\n", command.c_str(),
                 cli::error_text(st).c_str());
    return 1;
  }
  return 0;
}

std::string encode_shards(const std::vector<ShardEntry>& shards) {
  std::ostringstream out;
  for (const ShardEntry& e : shards) {
    out << e.file << ' ' << e.records << ' ' << e.first_key << ' ' << e.last_key << '\n';
  }
  return out.str();
}

std::vector<ShardEntry> decode_shards(const std::string& text) {
  std::vector<ShardEntry> out;
  std::istringstream in(text);
  for (ShardEntry e; in >> e.file >> e.records >> e.first_key >> e.last_key;) out.push_back(e);
  return out;
}

}  // namespace weaver::mpi
