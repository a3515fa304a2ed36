#include <cstdio>

#include "cli/cli.h"
#include "db/compact.h"

namespace weaver::cli {
namespace {

constexpr char kUsage[] =
    "usage: weaver compact DB [--memory BYTES]\n"
    "\n"
    "Joins every sharded table of database DB (the tables weaver-mpi writes, one\n"
    "shard file a rank) into one file by sorted append, and commits them all at\n"
    "once; the files are byte for byte what the single-process weaver writes for\n"
    "the same records.  Tables of one file are left as they are.  A failure\n"
    "leaves the database as it was.\n"
    "\n"
    "  --memory BYTES   bounds the shards' reader caches and the writer's (256M)\n";

}  // namespace

int cmd_compact(int argc, char** argv) {
  ParsedArgs args;
  Status st = parse_args(argc, argv, 2, {"memory"}, {}, &args);
  if (args.help) return std::fputs(kUsage, stdout), 0;
  if (!st.ok()) return usage_error("compact", st.message(), kUsage);
  if (args.positional.size() != 1) return usage_error("compact", "expected one DB", kUsage);
  MemoryBudget memory;
  st = memory_option(args, &memory);
  if (!st.ok()) return usage_error("compact", st.message(), kUsage);
  CompactResult r;
  st = compact_database(args.positional[0], memory, &r);
  if (!st.ok()) return report("compact", st);
  for (const CompactResult::Table& t : r.tables) {
    std::printf("table %s: %llu shards joined, %llu records, %llu bytes\n", t.name.c_str(),
                static_cast<unsigned long long>(t.shards),
                static_cast<unsigned long long>(t.records),
                static_cast<unsigned long long>(t.bytes));
  }
  if (r.tables.empty()) std::printf("%s has no sharded tables\n", args.positional[0].c_str());
  return 0;
}

}  // namespace weaver::cli
