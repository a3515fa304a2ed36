#include <algorithm>
#include <cstdio>
#include <cstring>

#include "cli/cli.h"
#include "cli/query_commands.h"
#include "db/database.h"
#include "db/octant_table.h"
#include "modeldb/model_table.h"

namespace weaver::cli {
namespace {

constexpr char kUsage[] =
    "usage: weaver query DB QUERY ARGS... [--units ticks|m] [--format MODE] [--memory BYTES]\n"
    "                                     [--threads N]\n"
    "\n"
    "Answers one question about the mesh in DB (for many, use 'weaver shell DB'):\n"
    "\n";

constexpr char kUsageTail[] =
    "  --memory BYTES        memory budget (default 256M): the table caches and a points\n"
    "                        batch\n"
    "  --threads N           threads that answer a --points batch (default: one a\n"
    "                        core); each reads the tables with its share of --memory\n"
    "A model database (weaver model import) answers 'material X Y Z' and 'material\n"
    "--points FILE' in metres, as 'weaver model material' does.\n"
    "\n"
    "examples:\n"
    "  weaver query DB locate 440000 576000 1000\n"
    "  weaver query DB material 30000 40000 -500 --units m\n"
    "  weaver query DB locate --points receivers.txt --units m --format csv > answers.csv\n"
    "  weaver query DB neighbors 1234 --all --format table\n";

}  // namespace

bool is_model_only(const std::string& db) {
  std::unique_ptr<Database> d;
  return Database::open(db, Database::Mode::kRead, false, &d).ok() && !d->has_table(kOctantTable) &&
         d->has_table(kModelTable);
}

Status check_target_kind(const std::string& db, bool mesh) {
  std::unique_ptr<Database> d;
  if (!Database::open(db, Database::Mode::kRead, false, &d).ok()) return Status::Ok();
  if (mesh && !d->has_table(kOctantTable) && d->has_table(kModelTable)) {  // is_model_only
    return Status::InvalidArgument(db + " is a model database, not a mesh: give the mesh a " +
                                   "database of its own (--model db:" + db + " reads the model)");
  }
  if (!mesh && d->has_table(kOctantTable)) {
    return Status::InvalidArgument(db + " is a mesh database: import the model into a " +
                                   "database of its own");
  }
  return Status::Ok();
}

int query_model(const std::string& db, const std::vector<std::string>& words,
                const std::string& memory) {
  if (words[0] != "material") {
    return usage_error("query", db + " is a model database: it answers 'material' only", kUsage);
  }
  std::vector<std::string> argv = {"weaver", "model", "material", db};
  for (size_t i = 1; i < words.size(); ++i) {
    if (words[i] == "--units" && i + 1 < words.size() && words[i + 1] == "m") {
      ++i;  // a model database's points are in metres anyway
      continue;
    }
    argv.push_back(words[i]);
  }
  if (!memory.empty()) argv.insert(argv.end(), {"--memory", memory});
  std::vector<char*> c;
  for (std::string& a : argv) c.push_back(a.data());
  return cmd_model(int(c.size()), c.data());
}

int cmd_query(int argc, char** argv) {
  // The database and --memory are read here; the rest is the query's.
  std::vector<std::string> words;
  ParsedArgs args;
  bool help = false;
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--help" || a == "-h") help = true;
    if ((a == "--memory" || a == "--threads") && i + 1 < argc) {
      args.values[a.substr(2)] = argv[++i];
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
  int threads = 1;
  if (st.ok()) st = threads_option(args, default_threads(), &threads);
  const std::string db = words[0];
  words.erase(words.begin());
  if (st.ok() && is_model_only(db)) {
    return query_model(db, words, args.values.count("memory") ? args.values.at("memory") : "");
  }
  if (st.ok()) st = check_query(words);
  if (!st.ok()) return usage_error("query", st.message(), kUsage);
  // A batch of points shares its lookups among threads, an Explorer each
  // with its share of the budget; one question takes the whole budget.
  const bool batch = std::find(words.begin(), words.end(), "--points") != words.end();
  if (!batch) threads = 1;
  const MemoryBudget each(
      std::max<uint64_t>(memory.bytes() / uint64_t(threads), MemoryBudget::kMinBytes));
  std::vector<std::unique_ptr<Explorer>> explorers(static_cast<size_t>(threads));
  QuerySettings settings;
  for (auto& e : explorers) {
    st = Explorer::open(db, each, &e);
    if (!st.ok()) return report("query", st);
    if (&e != &explorers[0]) settings.helpers.push_back(e.get());
  }
  return run_query(*explorers[0], words, settings, stdout, stderr, "weaver query");
}

}  // namespace weaver::cli
