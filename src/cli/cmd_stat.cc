#include <cstdio>

#include "cli/cli.h"
#include "db/database.h"
#include "query/table_stats.h"
#include "util/json_string.h"

namespace weaver::cli {
namespace {

constexpr char kUsage[] =
    "usage: weaver stat DB [--json]\n"
    "\n"
    "For every table of database DB: record count, leaves per level (octant\n"
    "tables), bytes on disk, bytes per record, size against the raw 8-byte key\n"
    "plus payload (below 100% for packed leaf pages), leaf page format and tree\n"
    "depth; for the octant table, its frame (tick_m: metres a tick; origin_m:\n"
    "where tick 0 lies; geo: lon, lat and azimuth of the origin, when known),\n"
    "model and ground; for the boundary table, its face counts and the least\n"
    "edge / vp.\n";

}  // namespace

int cmd_stat(int argc, char** argv) {
  ParsedArgs args;
  Status st = parse_args(argc, argv, 2, {}, {"json"}, &args);
  if (args.help) return std::fputs(kUsage, stdout), 0;
  if (!st.ok()) return usage_error("stat", st.message(), kUsage);
  if (args.positional.size() != 1) return usage_error("stat", "expected one DB", kUsage);
  std::unique_ptr<Database> db;
  st = Database::open(args.positional[0], Database::Mode::kRead, false, &db);
  if (!st.ok()) return report("stat", st);
  const bool json = args.flags.count("json") != 0;
  std::string out =
      json ? "{\"database\": " + json_string(args.positional[0]) + ", \"tables\": [" : "";
  bool first = true;
  for (const std::string& name : db->table_names()) {
    std::unique_ptr<BTree> t;
    TableStats s;
    st = db->open_table(name, 16ull << 20, &t);
    if (st.ok()) st = table_stats(name, *t, &s);
    if (!st.ok()) return report("stat", st);
    out += json ? (first ? "" : ", ") + stats_to_json(s) : stats_to_text(s);
    first = false;
  }
  if (json) out += "]}\n";
  if (!json && first) out = "database " + args.positional[0] + " has no tables\n";
  std::fputs(out.c_str(), stdout);
  return 0;
}

}  // namespace weaver::cli
