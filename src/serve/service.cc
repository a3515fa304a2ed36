#include "serve/service.h"

#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <memory>

#include "export/export.h"
#include "model/geo_frame.h"
#include "serve/params.h"
#include "serve/streams.h"
#include "serve/tiles.h"
#include "util/json_string.h"
#include "util/printable.h"

namespace weaver::serve {
namespace {

// A worker thread's open database: the Explorer, and which state it
// opened, to see a commit by.
struct Snapshot {
  std::string db;
  StateStamp state;
  std::unique_ptr<Explorer> ex;
  double extent[3] = {0, 0, 0};  // the domain's, ticks: found once a snapshot
  bool extent_known = false;
};
thread_local Snapshot t_snapshot;

// The domain's extents in this thread's snapshot (ex is its Explorer).
Status snapshot_extent(Explorer& ex, const double** extent) {
  Snapshot& s = t_snapshot;
  if (!s.extent_known) {
    WEAVER_RETURN_IF_ERROR(domain_extent(ex, s.extent));
    s.extent_known = true;
  }
  *extent = s.extent;
  return Status::Ok();
}

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  size_t from = 0;
  for (size_t at; (at = s.find(sep, from)) != std::string::npos; from = at + 1) {
    out.push_back(s.substr(from, at - from));
  }
  out.push_back(s.substr(from));
  return out;
}

int axis_of(const std::string& name) {
  return name == "x" ? 0 : name == "y" ? 1 : name == "z" ? 2 : -1;
}

std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

// A query's "weaver serve: message (see ...)" as the message alone.
std::string query_message(const std::string& err) {
  std::string message = err.substr(0, err.find('\n'));
  const size_t colon = message.find(": ");
  if (colon != std::string::npos) message = message.substr(colon + 2);
  const size_t see = message.find(" (see .help");
  if (see != std::string::npos) message = message.substr(0, see);
  return message;
}

// The paint a request asks for: ?color= (level) and ?summary= (the
// field's own), each from its fixed list.
Status paint_from(Explorer& ex, const Request& r, Paint* out) {
  const Params p(r);
  int field = 0, summary = 0;
  WEAVER_RETURN_IF_ERROR(
      p.choice("color", {"level", "edge", "vp", "vs", "rho", "qp", "qs"}, &field));
  WEAVER_RETURN_IF_ERROR(p.choice("summary", {"", "min", "max", "mean", "centre"}, &summary));
  static const char* const kFields[] = {"level", "edge", "vp", "vs", "rho", "qp", "qs"};
  static const char* const kSummaries[] = {"", "min", "max", "mean", "centre"};
  return paint_of(ex, kFields[field], kSummaries[summary], out);
}

// A section's plane in the domain's metres along axis.  ?z_mode=elevation
// takes a z plane's POSITION as an elevation (metres up: z = the mesh's
// top_elevation_m minus it), as `weaver slice --z elevation` does; depth is
// refused, since a plane at one depth below a ground is not flat.
Status plane_metres(Explorer& ex, const Params& p, int axis, double position, double* at_m) {
  int mode = 0;
  if (p.has("z_mode")) {
    WEAVER_RETURN_IF_ERROR(p.choice("z_mode", {"domain", "elevation", "depth"}, &mode));
    if (mode == 2) {
      return Status::InvalidArgument(
          "z_mode is domain or elevation for sections and tiles (a depth section would be "
          "curved)");
    }
  }
  *at_m = mode == 1 && axis == 2 ? ex.mesh().top_elevation() - position : position;
  return Status::Ok();
}

// The units, geo and z of a point question: ?units=ticks|m, ?geo=0|1,
// ?z_mode=domain|elevation|depth.
Status coordinate_options(const Params& p, ApiQuery* q) {
  int units = 0;
  WEAVER_RETURN_IF_ERROR(p.choice("units", {"ticks", "m"}, &units));
  q->metres = units == 1;
  WEAVER_RETURN_IF_ERROR(p.choice("z_mode", {"domain", "elevation", "depth"}, &q->z_mode));
  return p.flag("geo", &q->geo);
}

// A coordinate of a question: metres (or degrees) as a finite number,
// ticks as a whole number that fits a tick coordinate.
Status coordinate(const Params& p, const char* name, bool metres, double* v) {
  if (metres) return p.number(name, true, v);
  uint64_t t = 0;
  WEAVER_RETURN_IF_ERROR(p.whole(name, 0, UINT32_MAX, true, &t));
  *v = double(t);
  return Status::Ok();
}

// The kinds of ?kinds=faces,edges,corners,all as ApiQuery's bits.
Status neighbor_kinds(const Request& r, unsigned* mask) {
  *mask = 0;
  const auto it = r.query.find("kinds");
  if (it == r.query.end()) return Status::Ok();
  for (const std::string& k : split(it->second, ',')) {
    const unsigned bit = k == "faces"     ? 1
                         : k == "edges"   ? 2
                         : k == "corners" ? 4
                         : k == "all"     ? 7
                                          : 0;
    if (bit == 0) {
      return Status::InvalidArgument("kinds=" + quoted(it->second) +
                                     " is a list of faces, edges, corners and all");
    }
    *mask |= bit;
  }
  return Status::Ok();
}

Response status_response(const Status& st) {
  return error_response(st.is_invalid_argument() ? 400
                        : st.is_not_found()      ? 404
                                                 : 500,
                        st.message());
}

}  // namespace

Status Service::check() {
  Explorer* ex = nullptr;
  return explorer(&ex);
}

void Service::warm() {
  Explorer* ex = nullptr;
  (void)explorer(&ex);  // its tables' directories come with it; an error, at the first request
}

void Service::share_directories(Explorer& ex, const StateStamp& state) {
  std::lock_guard<std::mutex> lock(directories_mu_);
  if (!(directories_state_ == state)) {
    octant_directory_.reset(), node_directory_.reset(), aggregate_directory_.reset();
    directories_state_ = state;
  }
  // Built at most once a state: the first Explorer builds (within the
  // directories' share), the others take it.
  const auto share = [this](BTree& t, std::shared_ptr<const LeafDirectory>& slot) {
    if (!slot) {
      t.set_directory_budget(directories_ / 2);
      (void)t.prepare_lookups();  // a table that cannot have one is searched from its root
      slot = t.directory();
    }
    if (slot) t.share_directory(slot);
  };
  share(ex.mesh().octants(), octant_directory_);
  if (ex.has_nodes()) share(ex.mesh().nodes(), node_directory_);
  if (ex.mesh().has_aggregates()) share(ex.mesh().aggregates(), aggregate_directory_);
}

Status Service::explorer(Explorer** out) {
  struct stat st {};
  const std::string manifest = db_ + "/MANIFEST";
  if (::stat(manifest.c_str(), &st) != 0) {
    return Status::NotFound(db_ + ": not a weaver database (no MANIFEST)");
  }
  Snapshot& s = t_snapshot;
  const StateStamp now{st.st_ino, st.st_ctim};
  if (!s.ex || s.db != db_ || !(s.state == now)) {
    s.ex.reset();
    s.extent_known = false;
    // Split the budget among the threads that may each hold one.
    WEAVER_RETURN_IF_ERROR(Explorer::open(db_, memory_, &s.ex));
    s.db = db_, s.state = now;
    share_directories(*s.ex, now);
  }
  *out = s.ex.get();
  return Status::Ok();
}

// A batch of fewer bytes (about 10K points) is answered by its worker alone.
constexpr size_t kHelpedBody = 256 << 10;

Explorer* Service::helper(std::unique_lock<std::mutex>* lock) {
  *lock = std::unique_lock<std::mutex>(helper_mu_, std::try_to_lock);
  if (!lock->owns_lock()) return nullptr;
  const Snapshot& s = t_snapshot;  // the asking worker's: the helper reads the same
  if (!helper_ || !(helper_state_ == s.state)) {
    helper_.reset();
    if (!Explorer::open(db_, memory_, &helper_).ok()) return nullptr;  // the worker answers alone
    share_directories(*helper_, s.state);
    helper_state_ = s.state;
  }
  return helper_.get();
}

namespace {

// The page's three parts, none of them inline: the policy allows this
// origin's own files only, and no framing by another page.
Response page_part(const char* type, const char* text) {
  Response r{200, type, text, "no-cache"};
  r.extra_headers = {{"Content-Security-Policy",
                      "default-src 'self'; img-src 'self' data: blob:; "
                      "frame-ancestors 'none'; base-uri 'none'; form-action 'none'"},
                     {"X-Frame-Options", "DENY"}};
  return r;
}

}  // namespace

Response Service::handle(const Request& r) {
  std::string why;
  if (const int refused = check_caller(r, callers_, &why)) return error_response(refused, why);
  const bool get = r.method == "GET" || r.method == "HEAD";
  if (r.path == "/" || r.path == "/index.html" || r.path == "/page.css" || r.path == "/page.js") {
    if (!get) return error_response(405, "the page takes GET");
    if (r.path == "/page.css") return page_part("text/css; charset=utf-8", kPageCss);
    if (r.path == "/page.js") return page_part("text/javascript; charset=utf-8", kPageJs);
    return page_part("text/html; charset=utf-8", kPage);
  }
  if (r.path.rfind("/api/", 0) != 0) return error_response(404, "no such page: " + quoted(r.path));
  const bool post_route = r.path == "/api/points";
  if (post_route ? r.method != "POST" : !get) {
    Response no =
        error_response(405, printable(r.method, 16) + " " + quoted(r.path) + ": not taken here (" +
                                (post_route ? "POST" : "GET") + ")");
    no.extra_headers = {{"Allow", post_route ? "POST" : "GET, HEAD"}};
    return no;
  }
  Explorer* ex = nullptr;
  const Status st = explorer(&ex);
  if (!st.ok()) return error_response(503, st.message());
  return api(r, *ex);
}

Response Service::api(const Request& r, Explorer& ex) {
  const std::vector<std::string> parts = split(r.path.substr(1), '/');  // "api", ...
  const std::string& what = parts.size() > 1 ? parts[1] : "";
  if (what == "stat" && parts.size() == 2) return stat(ex);
  if (what == "section") return section(ex, parts, r);
  if (what == "tile") return tile(ex, parts, r);
  if (what == "export.vtu" && parts.size() == 2) return export_vtu(r);
  if (what == "geo" && parts.size() == 2) return geo(ex, r);
  const Params p(r);
  ApiQuery q;
  using Kind = ApiQuery::Kind;
  if (what == "locate" && parts.size() == 2) {
    Status st = coordinate_options(p, &q);
    const bool metres = q.metres || q.geo || q.z_mode != 0;
    static const char* const kAxes[] = {"x", "y", "z"};
    for (int a = 0; a < 3 && st.ok(); ++a) st = coordinate(p, kAxes[a], metres, &q.point[a]);
    if (!st.ok()) return status_response(st);
    return run(ex, q);
  }
  if (what == "points" && parts.size() == 2) {
    int kind = 0;
    Status st = p.choice("query", {"locate", "material", "node-at"}, &kind);
    if (st.ok()) st = coordinate_options(p, &q);
    if (!st.ok()) return status_response(st);
    q.kind = kind == 0 ? Kind::kLocate : kind == 1 ? Kind::kMaterial : Kind::kNodeAt;
    q.batch = true;
    return run_batch(ex, q, r);
  }
  static const std::map<std::string, Kind> kById = {{"element", Kind::kElement},
                                                    {"node", Kind::kNode},
                                                    {"neighbors", Kind::kNeighbors},
                                                    {"node-elements", Kind::kNodeElements},
                                                    {"depends", Kind::kDepends}};
  if (kById.count(what) && parts.size() == 3) {
    q.kind = kById.at(what);
    if (!parse_whole(parts[2], 0, UINT64_MAX, &q.id)) {
      return error_response(400, what + " takes an id (a whole number), not " + quoted(parts[2]));
    }
    Status st = coordinate_options(p, &q);
    if (st.ok() && q.kind == Kind::kNeighbors) st = neighbor_kinds(r, &q.neighbor_kinds);
    if (!st.ok()) return status_response(st);
    return run(ex, q);
  }
  if (what == "range" && parts.size() == 2) {
    q.kind = Kind::kRange;
    Status st = coordinate_options(p, &q);
    if (st.ok()) st = p.box("box", q.box);
    for (int i = 0; i < 6 && st.ok() && !q.metres; ++i) {
      if (!(q.box[i] >= 0 && q.box[i] <= UINT32_MAX && q.box[i] == std::floor(q.box[i]))) {
        st = Status::InvalidArgument("box in ticks is six whole numbers");
      }
    }
    q.list_limit = kMaxListed;
    if (st.ok()) st = p.flag("list", &q.list);
    if (st.ok()) st = p.whole("limit", 1, kMaxListed, false, &q.list_limit);
    if (st.ok()) st = p.whole("from", 0, UINT64_MAX, false, &q.list_from);
    if (!st.ok()) return status_response(st);
    return q.list ? run_list(ex, q) : run(ex, q);
  }
  return error_response(404, "no such API route: " + quoted(r.path));
}

namespace {

// How a query that ended with code, having printed `printed` bytes and err,
// is answered: 200 when it printed its answer (a batch with bad lines ends
// 1 and still answers every row), 400 for a usage error, 404 for what does
// not exist, 500 otherwise.
Response outcome(int code, uint64_t printed, const std::string& err) {
  const std::string message = query_message(err);
  if (code == 0 || (code == 1 && printed > 0)) return Response(200);
  if (code == 2) return error_response(400, message);
  const bool missing = message.find("does not exist") != std::string::npos ||
                       message.find("no mesh yet") != std::string::npos ||
                       message.find("not georeferenced") != std::string::npos ||
                       message.find("has no material") != std::string::npos;
  return error_response(missing ? 404 : 500, message);
}

}  // namespace

Response Service::run(Explorer& ex, const ApiQuery& q) {
  std::string out, err;
  std::FILE* o = string_stream(&out);
  static const std::string kNoPoints;  // these questions read no points
  std::FILE* in = points_stream(kNoPoints);
  const int code = o && in ? query_(ex, {}, q, in, o, &err) : 1;
  if (in) std::fclose(in);
  if (o) std::fclose(o);  // flushes into out
  Response res = outcome(code, out.size(), err);
  if (res.status == 200) res.body = std::move(out);
  return res;
}

Response Service::run_batch(Explorer& ex, const ApiQuery& q, const Request& r) {
  Response res(200, "application/json");
  // Run by this worker as it sends the answer, before its next request:
  // ex and r are still this request's.
  res.stream = [this, &ex, &r, q](BodySink& sink) {
    uint64_t printed = 0;
    std::string err;
    std::FILE* o = sink_stream(&sink, &printed);
    std::FILE* in = points_stream(r.body);
    std::unique_lock<std::mutex> lock;
    std::vector<Explorer*> helpers;
    ApiQuery asked = q;
    std::unique_lock<std::mutex> lane;
    if (r.body.size() >= kHelpedBody) {
      if (Explorer* h = helper(&lock)) helpers.push_back(h);
      lane = std::unique_lock<std::mutex>(lane_mu_, std::try_to_lock);
      if (lane.owns_lock()) asked.batch_points = lane_points_;
    }
    const int code = o && in ? query_(ex, helpers, asked, in, o, &err) : 1;
    if (in) std::fclose(in);
    if (o && std::fclose(o) != 0 && code == 0) return error_response(500, "the client left");
    return outcome(code, printed, err);
  };
  return res;
}

Response Service::run_list(Explorer& ex, const ApiQuery& asked) {
  Response res(200, "application/json");
  res.stream = [this, &ex, asked](BodySink& sink) {
    ApiQuery q = asked;
    uint64_t printed = 0, next = UINT64_MAX, count = 0;
    q.list_next = &next, q.list_count = &count;
    std::string err;
    std::FILE* o = sink_stream(&sink, &printed);
    static const std::string kNoPoints;
    std::FILE* in = points_stream(kNoPoints);
    int code = 1;
    if (o && in) {
      std::fputs("{\"elements\": ", o);
      code = query_(ex, {}, q, in, o, &err);
      const bool cut = next != UINT64_MAX;
      std::fprintf(o, ", \"count\": %llu, \"truncated\": %s, \"next\": %s}\n",
                   (unsigned long long)count, cut ? "true" : "false",
                   cut ? std::to_string(next).c_str() : "null");
    }
    if (in) std::fclose(in);
    if (o && std::fclose(o) != 0 && code == 0) return error_response(500, "the client left");
    return code == 0 ? Response(200) : outcome(code, 0, err);
  };
  return res;
}

Response Service::stat(Explorer& ex) {
  const double* extent = nullptr;
  const Status st = snapshot_extent(ex, &extent);
  if (!st.ok()) return status_response(st);
  const Units& u = ex.units();
  const char* kind = ex.mesh().is_model() ? "model" : ex.has_nodes() ? "mesh" : "octree";
  std::string j = "{\"database\": " + json_string(db_) + ", \"kind\": \"" + kind + "\"" +
                  ", \"elements\": " + std::to_string(ex.element_count()) +
                  ", \"nodes\": " + std::to_string(ex.node_count()) +
                  ", \"tick_m\": " + number(u.tick_m) + ", \"origin_m\": [";
  for (int a = 0; a < 3; ++a) j += (a ? ", " : "") + number(u.origin_m[a]);
  j += "], \"extent_m\": [";
  for (int a = 0; a < 3; ++a) j += (a ? ", " : "") + number(extent[a] * u.tick_m);
  j += "], \"geo\": " + json_string(u.geo) + ", \"fields\": [\"level\", \"edge\"";
  if (ex.mesh().has_material()) j += ", \"vp\", \"vs\", \"rho\"";
  if (ex.mesh().has_q()) j += ", \"qp\", \"qs\"";
  // The elevation of z = 0 for a mesh under a ground (z_mode=elevation
  // counts from it); null for a flat-topped box.
  j += "], \"top_elevation_m\": ";
  j += ex.mesh().has_ground() ? number(ex.mesh().top_elevation()) : "null";
  // The finest level the aggregate table summarises (null without one).
  j += ", \"aggregates\": ";
  j += ex.aggregate_finest() < 0 ? "null" : std::to_string(ex.aggregate_finest());
  return {200, "application/json", j + "}\n"};
}

Response Service::section(Explorer& ex, const std::vector<std::string>& parts, const Request& r) {
  double at = 0;
  if (parts.size() != 4 || axis_of(parts[2]) < 0 || !parse_finite(parts[3], &at)) {
    return error_response(400, "a section is /api/section/AXIS/POSITION (x, y or z; metres)");
  }
  Section s;
  FieldRange range;
  Paint paint;
  Status st = paint_from(ex, r, &paint);
  const double* extent = nullptr;
  if (st.ok()) st = plane_metres(ex, Params(r), axis_of(parts[2]), at, &at);
  if (st.ok()) st = snapshot_extent(ex, &extent);
  if (st.ok()) st = section_of(ex, extent, axis_of(parts[2]), at, &s);
  if (st.ok()) st = shared_range(ex, s, paint, &range);
  if (!st.ok()) return status_response(st);
  const Units& u = ex.units();
  std::string j =
      "{\"axis\": \"" + parts[2] + "\", \"at_m\": " + number(u.origin_m[s.axis] + s.at * u.tick_m) +
      ", \"at_ticks\": " + std::to_string(s.at) + ", \"u\": \"" + "xyz"[s.u] + "\", \"v\": \"" +
      "xyz"[s.v] + "\", \"down\": " + (s.down ? "true" : "false") +
      ", \"side_m\": " + number(s.side * u.tick_m) + ", \"origin_m\": [" + number(u.origin_m[s.u]) +
      ", " + number(u.origin_m[s.v]) + "], \"extent_m\": [" + number(s.extent[s.u] * u.tick_m) +
      ", " + number(s.extent[s.v] * u.tick_m) + "], \"color\": " + json_string(paint.field) +
      ", \"summary\": \"" + summary_name(paint.summary) +
      "\", \"caption\": " + json_string(paint_caption(paint)) + ", \"min\": " + number(range.min) +
      ", \"max\": " + number(range.max) + ", \"samples\": " + std::to_string(range.samples) + "}\n";
  return {200, "application/json", j};
}

Response Service::tile(Explorer& ex, const std::vector<std::string>& parts, const Request& r) {
  double at = 0;
  uint64_t zoom = 0, x = 0, y = 0;
  const std::string last = parts.size() == 7 ? parts[6] : "";
  const bool png = last.size() > 4 && last.compare(last.size() - 4, 4, ".png") == 0;
  if (parts.size() != 7 || axis_of(parts[2]) < 0 || !parse_finite(parts[3], &at) ||
      !parse_whole(parts[4], 0, 30, &zoom) || !png) {
    return error_response(400, "a tile is /api/tile/AXIS/POSITION/ZOOM/X/Y.png (zoom 0 to 30)");
  }
  const uint64_t n = uint64_t{1} << zoom;
  if (!parse_whole(parts[5], 0, n - 1, &x) ||
      !parse_whole(last.substr(0, last.size() - 4), 0, n - 1, &y)) {
    return error_response(404, "zoom " + std::to_string(zoom) + " has tiles 0 to " +
                                   std::to_string(n - 1) + " across and down");
  }
  const Params p(r);
  FieldRange range;
  bool danglings = false;
  Status st = p.number("min", false, &range.min);
  if (st.ok()) st = p.number("max", false, &range.max);
  if (st.ok()) st = p.flag("danglings", &danglings);
  if (st.ok() && p.has("min") != p.has("max")) {
    st = Status::InvalidArgument("min and max go together");
  }
  Section s;
  Paint paint;
  if (st.ok()) st = paint_from(ex, r, &paint);
  const double* extent = nullptr;
  if (st.ok()) st = plane_metres(ex, p, axis_of(parts[2]), at, &at);
  if (st.ok()) st = snapshot_extent(ex, &extent);
  if (st.ok()) st = section_of(ex, extent, axis_of(parts[2]), at, &s);
  if (st.ok() && !p.has("min")) st = shared_range(ex, s, paint, &range);
  std::string bytes;
  if (st.ok()) {
    st = render_tile(ex, s, paint, range.min, range.max, int(zoom), int64_t(x), int64_t(y), &bytes,
                     danglings);
  }
  if (!st.ok()) return status_response(st);
  return {200, "image/png", std::move(bytes)};
}

Status Service::shared_range(Explorer& ex, const Section& s, const Paint& paint,
                             FieldRange* range) {
  const std::string key = std::to_string(s.axis) + " " + std::to_string(s.at) + " " + paint.field +
                          " " + summary_name(paint.summary);
  const StateStamp state = t_snapshot.state;  // ex's
  {
    std::lock_guard<std::mutex> lock(ranges_mu_);
    if (!(ranges_state_ == state)) ranges_.clear(), ranges_state_ = state;
    const auto it = ranges_.find(key);
    if (it != ranges_.end()) return *range = it->second, Status::Ok();
  }
  // Found outside the lock: two workers asking at once both work it out,
  // and find the same.
  WEAVER_RETURN_IF_ERROR(field_range(ex, s, paint, range));
  std::lock_guard<std::mutex> lock(ranges_mu_);
  if (!(ranges_state_ == state)) return Status::Ok();  // a newer state came meanwhile
  if (ranges_.size() >= kMaxRanges) ranges_.clear();
  ranges_[key] = *range;
  return Status::Ok();
}

Response Service::geo(Explorer& ex, const Request& r) {
  double x = 0, y = 0;
  const Params p(r);
  Status st = p.number("x", true, &x);
  if (st.ok()) st = p.number("y", true, &y);
  if (!st.ok()) return error_response(400, "geo takes x and y in metres: " + st.message());
  GeoFrame frame;
  if (ex.units().geo.empty()) return error_response(404, "this database is not georeferenced");
  st = GeoFrame::parse(ex.units().geo, &frame);
  if (!st.ok()) return status_response(st);
  double lon = 0, lat = 0;
  frame.to_geo(x, y, &lon, &lat);
  return {200, "application/json",
          "{\"x\": " + number(x) + ", \"y\": " + number(y) + ", \"lon\": " + number(lon) +
              ", \"lat\": " + number(lat) + "}\n"};
}

// The export opens the database itself (not this thread's Explorer), so it
// counts its cap on the state it writes.
Response Service::export_vtu(const Request& r) {
  ExportOptions o;
  const Status given = Params(r).box("box", o.box);
  if (!given.ok()) return error_response(400, given.message() + " (metres)");
  // Written by the exporter into a scratch directory of its own inside the
  // database (a writer's leftover pattern: removed by the next writer if
  // this process dies), opened, and removed at once: the open file is
  // streamed, never held whole.
  const std::string& scratch = scratch_.empty() ? db_ : scratch_;
  std::string dir = scratch + "/tmp-serve-XXXXXX";
  if (::mkdtemp(dir.data()) == nullptr) {
    return error_response(500, "cannot make a scratch directory in " + scratch + ": " +
                                   std::strerror(errno) + " (weaver serve --scratch DIR)");
  }
  o.format = ExportFormat::kVtu;
  o.out = dir + "/region.vtu";
  o.has_box = true;
  o.max_elements = kMaxExportElements;
  o.memory = memory_;
  ExportResult result;
  const Status st = export_mesh(db_, o, &result);
  std::shared_ptr<std::FILE> file(st.ok() ? std::fopen(o.out.c_str(), "rb") : nullptr,
                                  [](std::FILE* f) {
                                    if (f) std::fclose(f);
                                  });
  std::error_code ec;
  std::filesystem::remove_all(dir, ec);
  if (result.elements > kMaxExportElements) {
    return error_response(
        413, std::to_string(result.elements) + " elements share a point with the box, more than " +
                 std::to_string(kMaxExportElements) + ": use weaver export --format vtu --box");
  }
  if (!st.ok()) return status_response(st);
  if (result.elements == 0) return error_response(404, "no element shares a point with the box");
  if (!file) return error_response(500, "cannot read the region written");
  Response res{200, "application/xml", "", "no-store", "region.vtu"};
  res.stream = [file](BodySink& sink) {
    std::vector<char> buf(256 << 10);
    for (size_t n; (n = std::fread(buf.data(), 1, buf.size(), file.get())) > 0;) {
      if (!sink.write(buf.data(), n)) return error_response(500, "the client left");
    }
    return std::ferror(file.get()) ? error_response(500, "reading the region written")
                                   : Response(200);
  };
  return res;
}

}  // namespace weaver::serve
