// weaver-mpi export: raw --parts N or pvtu with N pieces, one part a rank,
// the files 'weaver export --parts N' writes (export/export.h:
// export_parts_begin, export_one_part, export_parts_end).  Rank 0 starts the
// output and, once every rank has written its part, finishes it (raw:
// parts.json and the rename into place; pvtu: the index), or, when a rank
// failed, removes it and names the rank.
#include <chrono>
#include <cstdio>
#include <sstream>

#include "cli/cli.h"
#include "export/export.h"
#include "mpi/mpi_commands.h"
#include "mpi/shards.h"

namespace weaver::mpi {
namespace {

constexpr char kUsage[] =
    "usage: mpirun -np N weaver-mpi export DB --format raw|pvtu --out PATH [--parts N]\n"
    "                                         [--units m|ticks] [--box ...] [--memory BYTES]\n"
    "\n"
    "The per-part files of 'weaver export DB --format raw|pvtu --parts N', byte\n"
    "for byte, rank r writing part r: raw, PATH/part-0000r/ (local numbering,\n"
    "global ids, the part's dangling constraints and its shared nodes) and then\n"
    "PATH/parts.json; pvtu, the piece PATH_r.vtu in the directory beside the\n"
    "index PATH, written last.  The parts are those of the stored partition\n"
    "('weaver partition') when it has N parts, else N runs of element ids of\n"
    "equal count.  A part's shared nodes are found from its own elements and\n"
    "the leaves around them, not from the whole mesh.  DB and PATH must be on a\n"
    "file system every rank sees.  On one rank (no mpirun) it writes what\n"
    "'weaver export' does with --parts 1.  The other options are weaver export's.\n"
    "\n"
    "  --parts N        the number of ranks (the default; another N is refused)\n"
    "  --memory BYTES   each rank's budget (default 256M), cut as weaver export's\n";

bool one_part_a_rank(ExportFormat f) { return f == ExportFormat::kRaw || f == ExportFormat::kPvtu; }

// Rank 0 ends the export: the ranks' lines, then the finished output or the
// first failing rank's error.  Returns the exit status.
int finish(const Comm& comm, const std::string& db, const ExportOptions& o,
           const std::vector<std::string>& all, std::chrono::steady_clock::time_point t0) {
  std::string failed;
  for (size_t r = 0; r < all.size(); ++r) {
    const size_t cut = all[r].find('\x1f');
    std::printf("%s\n", all[r].substr(cut + 1).c_str());
    if (failed.empty() && cut > 0) {
      failed = "rank " + std::to_string(r) + ": " + all[r].substr(0, cut);
    }
  }
  ExportResult end;
  const Status st = export_parts_end(db, o, failed.empty(), &end);
  if (failed.empty() && !st.ok()) failed = "rank 0: " + cli::error_text(st);
  if (!failed.empty()) {
    std::fprintf(stderr, "weaver-mpi export: %s\n", failed.c_str());
    return 1;
  }
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("export: %u parts in %.2fs on %d ranks\n", o.parts, secs, comm.size());
  return 0;
}

// One rank (weaver-mpi without mpirun): what 'weaver export --parts 1' writes
// (for raw, one export in PATH, not a part directory).
int export_alone(const std::string& db, const ExportOptions& o,
                 std::chrono::steady_clock::time_point t0) {
  ExportResult r;
  const Status st = export_mesh(db, o, &r);
  if (!st.ok()) {
    std::fprintf(stderr, "weaver-mpi export: rank 0: %s\n", cli::error_text(st).c_str());
    return 1;
  }
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("rank 0  part of %llu nodes and %llu elements, wrote %llu B, peak RSS %llu B\n",
              (unsigned long long)r.nodes, (unsigned long long)r.elements,
              (unsigned long long)r.bytes, (unsigned long long)peak_rss_bytes());
  std::printf("export: 1 parts in %.2fs on 1 ranks\n", secs);
  return 0;
}

}  // namespace

int export_parts(const Comm& comm, int argc, char** argv) {
  ParsedArgs args;
  Status st =
      parse_args(argc, argv, 2, {"memory", "format", "out", "units", "box", "parts"}, {}, &args);
  if (args.help) return std::fputs(kUsage, stdout), 0;
  if (!st.ok()) return cli::usage_error("export", st.message(), kUsage);
  if (args.positional.size() != 1) return cli::usage_error("export", "expected one DB", kUsage);
  ExportOptions o;
  st = cli::parse_export_options(args, &o);
  if (!st.ok()) return cli::usage_error("export", st.message(), kUsage);
  if (!one_part_a_rank(o.format)) {
    return cli::usage_error("export", "writes raw or pvtu, one part a rank", kUsage);
  }
  if (!args.values.count("parts")) o.parts = static_cast<uint32_t>(comm.size());
  if (o.parts != static_cast<uint32_t>(comm.size())) {
    return cli::usage_error(
        "export", "--parts must be the number of ranks (" + std::to_string(comm.size()) + ")",
        kUsage);
  }
  const std::string& db = args.positional[0];
  const auto t0 = std::chrono::steady_clock::now();
  if (comm.size() == 1) return export_alone(db, o, t0);
  st = comm.rank() == 0 ? export_parts_begin(o) : Status::Ok();
  const std::string begun = comm.broadcast(st.ok() ? std::string() : cli::error_text(st));
  if (!begun.empty()) {
    if (comm.rank() == 0) std::fprintf(stderr, "weaver-mpi export: rank 0: %s\n", begun.c_str());
    return 1;
  }
  ExportResult r;
  st = export_one_part(db, o, static_cast<uint32_t>(comm.rank()), &r);
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::ostringstream line;
  line.precision(3);
  line << std::fixed << "rank " << comm.rank() << "  part of " << r.nodes << " nodes and "
       << r.elements << " elements in " << secs << "s, wrote " << r.bytes << " B, peak RSS "
       << peak_rss_bytes() << " B";
  const std::vector<std::string> all =
      comm.gather((st.ok() ? std::string() : cli::error_text(st)) + '\x1f' + line.str());
  const int code = comm.rank() == 0 ? finish(comm, db, o, all, t0) : 0;
  std::fflush(stdout);
  return static_cast<int>(comm.broadcast(uint64_t(code)));
}

}  // namespace weaver::mpi
