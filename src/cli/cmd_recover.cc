#include <cstdio>

#include "cli/cli.h"
#include "db/database.h"

namespace weaver::cli {
namespace {

constexpr char kUsage[] =
    "usage: weaver recover DB\n"
    "\n"
    "Rebuilds the MANIFEST of database DB when it is missing or damaged (a\n"
    "damaged one is kept as MANIFEST.damaged), from the table files themselves:\n"
    "every '<table>-<n>.bt' file is checked page by page, and per table the\n"
    "newest file that checks out becomes the live table.  The shard files of\n"
    "a sharded table ('<table>-<n>.<rank>.bt', from weaver-mpi) count as one\n"
    "version only when all of its shards are there (each keeps its place among\n"
    "them).  A table older than the table it derives from (nodes older than\n"
    "octants) is left out.  Files not used are renamed '<file>.unused', never\n"
    "deleted.  Refuses a database whose MANIFEST is intact.  Run 'weaver verify\n"
    "DB' afterwards.\n";

}  // namespace

int cmd_recover(int argc, char** argv) {
  ParsedArgs args;
  Status st = parse_args(argc, argv, 2, {}, {}, &args);
  if (args.help) return std::fputs(kUsage, stdout), 0;
  if (!st.ok()) return usage_error("recover", st.message(), kUsage);
  if (args.positional.size() != 1) return usage_error("recover", "expected one DB", kUsage);
  const std::string& dir = args.positional[0];
  RecoverReport r;
  st = Database::recover(dir, &r);
  if (!st.ok()) return report("recover", st);
  if (!r.manifest_set_aside.empty()) {
    std::printf("kept the damaged manifest as %s/%s\n", dir.c_str(), r.manifest_set_aside.c_str());
  }
  for (const std::string& t : r.tables) std::printf("recovered table %s\n", t.c_str());
  for (const std::string& f : r.set_aside) std::printf("set aside %s\n", f.c_str());
  std::printf("%s: new MANIFEST with %zu table%s; run 'weaver verify %s' to check the mesh\n",
              dir.c_str(), r.tables.size(), r.tables.size() == 1 ? "" : "s", dir.c_str());
  return 0;
}

}  // namespace weaver::cli
