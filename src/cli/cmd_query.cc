#include <cstdio>
#include <cstring>

#include "cli/cli.h"
#include "cli/query_commands.h"

namespace weaver::cli {
namespace {

constexpr char kUsage[] =
    "usage: weaver query DB QUERY ARGS... [--units ticks|m] [--format MODE] [--memory BYTES]\n"
    "\n"
    "Answers one question about the mesh in DB (for many, use 'weaver shell DB'):\n"
    "\n";

constexpr char kUsageTail[] =
    "  --memory BYTES        memory budget (default 256M): the table caches and a points\n"
    "                        batch\n"
    "\n"
    "examples:\n"
    "  weaver query DB locate 440000 576000 1000\n"
    "  weaver query DB material 30000 40000 -500 --units m\n"
    "  weaver query DB locate --points receivers.txt --units m --format csv > answers.csv\n"
    "  weaver query DB neighbors 1234 --all --format table\n";

}  // namespace

int cmd_query(int argc, char** argv) {
  // The database and --memory are read here; the rest is the query's.
  std::vector<std::string> words;
  ParsedArgs args;
  bool help = false;
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--help" || a == "-h") help = true;
    if (a == "--memory" && i + 1 < argc) {
      args.values["memory"] = argv[++i];
      continue;
    }
    words.push_back(a);
  }
  if (help) {
    std::printf("%s%s%s", kUsage, kQueryHelp, kUsageTail);
    return 0;
  }
  if (words.size() < 2) return usage_error("query", "expected DB and a query", kUsage);
  MemoryBudget memory;
  Status st = memory_option(args, &memory);
  const std::string db = words[0];
  words.erase(words.begin());
  if (st.ok()) st = check_query(words);
  if (!st.ok()) return usage_error("query", st.message(), kUsage);
  std::unique_ptr<Explorer> ex;
  st = Explorer::open(db, memory, &ex);
  if (!st.ok()) return report("query", st);
  return run_query(*ex, words, QuerySettings{}, stdout, stderr, "weaver query");
}

}  // namespace weaver::cli
