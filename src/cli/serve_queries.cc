#include "cli/serve_queries.h"

#include <cstdio>

#include "cli/query_commands.h"
#include "serve/streams.h"

namespace weaver::cli {
namespace {

// A coordinate of q as a word of the query: its own text, printed here
// from a number the service parsed.
std::string coordinate_word(double v, bool metres) {
  if (!metres) return std::to_string(uint64_t(v));  // whole ticks, checked by the service
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

// The query q asks, as parse_args would leave it: every word made here
// from q's typed values, none taken from a client.
ParsedArgs query_args(const serve::ApiQuery& q) {
  using Kind = serve::ApiQuery::Kind;
  static const char* const kNames[] = {"locate",    "material",      "node-at", "element", "node",
                                       "neighbors", "node-elements", "depends", "range"};
  ParsedArgs a;
  a.positional = {kNames[int(q.kind)]};
  const bool metres = q.metres || q.geo || q.z_mode != 0;
  if (q.kind == Kind::kLocate || q.kind == Kind::kMaterial || q.kind == Kind::kNodeAt) {
    if (q.batch) a.values["points"] = "-";
    for (int i = 0; i < 3 && !q.batch; ++i)
      a.positional.push_back(coordinate_word(q.point[i], metres));
  } else if (q.kind == Kind::kRange) {
    for (double v : q.box) a.positional.push_back(coordinate_word(v, metres));
    if (q.list) a.flags.insert("list");
  } else {
    a.positional.push_back(std::to_string(q.id));
  }
  if (q.kind == Kind::kNeighbors) {
    static const char* const kKinds[] = {"faces", "edges", "corners"};
    for (int k = 0; k < 3; ++k) {
      if (q.neighbor_kinds & (1u << k)) a.flags.insert(kKinds[k]);
    }
  }
  if (q.metres) a.values["units"] = "m";
  if (q.geo) a.flags.insert("geo");
  static const char* const kZModes[] = {"domain", "elevation", "depth"};
  if (q.z_mode != 0) a.values["z"] = kZModes[q.z_mode];
  a.values["format"] = "json";
  return a;
}

// A query of the API on an open Explorer, its points read from points,
// its answer printed to out and the first of its errors captured.
int run_query_on(Explorer& ex, const std::vector<Explorer*>& helpers, const serve::ApiQuery& q,
                 std::FILE* points, std::FILE* out, std::string* err) {
  err->clear();
  std::FILE* e = serve::string_stream(err, serve::kErrorHeld);
  QuerySettings settings;
  settings.points_stdin = points;
  settings.helpers = helpers;
  settings.batch_points = q.batch_points;
  if (q.list) {
    settings.list_from = q.list_from, settings.list_limit = q.list_limit;
    settings.list_next = q.list_next, settings.list_count = q.list_count;
  }
  const int code = e ? run_parsed_query(ex, query_args(q), settings, out, e, "weaver serve") : 1;
  if (e) std::fclose(e);  // flushes into *err
  return code;
}

}  // namespace

serve::QueryRunner serve_query_runner() { return run_query_on; }

}  // namespace weaver::cli
