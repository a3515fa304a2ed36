#include "serve/service.h"

#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>

#include "export/export.h"
#include "model/geo_frame.h"
#include "serve/streams.h"
#include "serve/tiles.h"
#include "util/json_string.h"

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

bool parse_number(const std::string& s, double* v) {
  char* end = nullptr;
  *v = std::strtod(s.c_str(), &end);
  return !s.empty() && *end == '\0' && std::isfinite(*v);
}

bool parse_whole(const std::string& s, int64_t lo, int64_t hi, int64_t* v) {
  char* end = nullptr;
  const long long n = std::strtoll(s.c_str(), &end, 10);
  *v = n;
  return !s.empty() && *end == '\0' && n >= lo && n <= hi;
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
// field's own).
Status paint_from(Explorer& ex, const Request& r, Paint* out) {
  const auto arg = [&r](const char* k, const char* none) {
    return r.query.count(k) ? r.query.at(k) : std::string(none);
  };
  return paint_of(ex, arg("color", "level"), arg("summary", ""), out);
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

Response Service::handle(const Request& r) {
  if (r.path == "/" || r.path == "/index.html") {
    if (r.method != "GET") return error_response(405, "the page takes GET");
    return {200, "text/html; charset=utf-8", kPage, "no-cache"};
  }
  if (r.path.rfind("/api/", 0) != 0) return error_response(404, "no such page: " + r.path);
  if (r.method != "GET" && !(r.method == "POST" && r.path == "/api/points")) {
    return error_response(405, r.method + " " + r.path + ": not taken here");
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
  if (what == "export.vtu" && parts.size() == 2) return export_vtu(ex, r);
  if (what == "geo" && parts.size() == 2) return geo(ex, r);
  if (what == "locate" && parts.size() == 2) {
    for (const char* c : {"x", "y", "z"}) {
      if (!r.query.count(c)) return error_response(400, "locate takes x, y and z");
    }
    return run(ex, {"locate", r.query.at("x"), r.query.at("y"), r.query.at("z")}, r);
  }
  if (what == "points" && parts.size() == 2) {
    const std::string q = r.query.count("query") ? r.query.at("query") : "locate";
    if (q != "locate" && q != "material" && q != "node-at") {
      return error_response(400, "query is locate, material or node-at, not '" + q + "'");
    }
    return run_batch(ex, {q, "--points", "-"}, r);
  }
  const bool by_id = what == "element" || what == "node" || what == "neighbors" ||
                     what == "node-elements" || what == "depends";
  if (by_id && parts.size() == 3) {
    std::vector<std::string> words = {what, parts[2]};
    if (what == "neighbors" && r.query.count("kinds")) {
      for (const std::string& k : split(r.query.at("kinds"), ',')) words.push_back("--" + k);
    }
    return run(ex, words, r);
  }
  if (what == "range" && parts.size() == 2) {
    if (!r.query.count("box")) return error_response(400, "range takes box=X0,Y0,Z0,X1,Y1,Z1");
    std::vector<std::string> words = split(r.query.at("box"), ',');
    if (words.size() != 6) return error_response(400, "box is six numbers: X0,Y0,Z0,X1,Y1,Z1");
    words.insert(words.begin(), "range");
    if (r.query.count("list") && r.query.at("list") != "0") words.push_back("--list");
    return run(ex, words, r);
  }
  return error_response(404, "no such API route: " + r.path);
}

namespace {

// The words of a query as the API's options ask: units, geo, JSON.
std::vector<std::string> with_options(std::vector<std::string> words, const Request& r) {
  if (r.query.count("units")) words.insert(words.end(), {"--units", r.query.at("units")});
  if (r.query.count("geo") && r.query.at("geo") != "0") words.push_back("--geo");
  words.insert(words.end(), {"--format", "json"});
  return words;
}

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

Response Service::run(Explorer& ex, std::vector<std::string> words, const Request& r) {
  std::string out, err;
  std::FILE* o = string_stream(&out);
  static const std::string kNoPoints;  // these questions read no points
  std::FILE* in = points_stream(kNoPoints);
  const int code = o && in ? query_(ex, {}, with_options(std::move(words), r), in, o, &err) : 1;
  if (in) std::fclose(in);
  if (o) std::fclose(o);  // flushes into out
  Response res = outcome(code, out.size(), err);
  if (res.status == 200) res.body = std::move(out);
  return res;
}

Response Service::run_batch(Explorer& ex, std::vector<std::string> words, const Request& r) {
  Response res(200, "application/json");
  // Run by this worker as it sends the answer, before its next request:
  // ex and r are still this request's.
  res.stream = [this, &ex, &r, words = with_options(std::move(words), r)](BodySink& sink) {
    uint64_t printed = 0;
    std::string err;
    std::FILE* o = sink_stream(&sink, &printed);
    std::FILE* in = points_stream(r.body);
    std::unique_lock<std::mutex> lock;
    std::vector<Explorer*> helpers;
    if (r.body.size() >= kHelpedBody) {
      if (Explorer* h = helper(&lock)) helpers.push_back(h);
    }
    const int code = o && in ? query_(ex, helpers, words, in, o, &err) : 1;
    if (in) std::fclose(in);
    if (o && std::fclose(o) != 0 && code == 0) return error_response(500, "the client left");
    return outcome(code, printed, err);
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
  // The finest level the aggregate table summarises (null without one).
  j += "], \"aggregates\": ";
  j += ex.aggregate_finest() < 0 ? "null" : std::to_string(ex.aggregate_finest());
  return {200, "application/json", j + "}\n"};
}

Response Service::section(Explorer& ex, const std::vector<std::string>& parts, const Request& r) {
  double at = 0;
  if (parts.size() != 4 || axis_of(parts[2]) < 0 || !parse_number(parts[3], &at)) {
    return error_response(400, "a section is /api/section/AXIS/POSITION (x, y or z; metres)");
  }
  Section s;
  FieldRange range;
  Paint paint;
  Status st = paint_from(ex, r, &paint);
  const double* extent = nullptr;
  if (st.ok()) st = snapshot_extent(ex, &extent);
  if (st.ok()) st = section_of(ex, extent, axis_of(parts[2]), at, &s);
  if (st.ok()) st = field_range(ex, s, paint, &range);
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
  int64_t zoom = 0, x = 0, y = 0;
  const std::string last = parts.size() == 7 ? parts[6] : "";
  const bool png = last.size() > 4 && last.compare(last.size() - 4, 4, ".png") == 0;
  if (parts.size() != 7 || axis_of(parts[2]) < 0 || !parse_number(parts[3], &at) ||
      !parse_whole(parts[4], 0, 30, &zoom) || !png) {
    return error_response(400, "a tile is /api/tile/AXIS/POSITION/ZOOM/X/Y.png (zoom 0 to 30)");
  }
  const int64_t n = int64_t{1} << zoom;
  if (!parse_whole(parts[5], 0, n - 1, &x) ||
      !parse_whole(last.substr(0, last.size() - 4), 0, n - 1, &y)) {
    return error_response(404, "zoom " + std::to_string(zoom) + " has tiles 0 to " +
                                   std::to_string(n - 1) + " across and down");
  }
  Section s;
  Paint paint;
  Status st = paint_from(ex, r, &paint);
  const double* extent = nullptr;
  if (st.ok()) st = snapshot_extent(ex, &extent);
  if (st.ok()) st = section_of(ex, extent, axis_of(parts[2]), at, &s);
  FieldRange range;
  const bool given = r.query.count("min") && r.query.count("max");
  if (given && (!parse_number(r.query.at("min"), &range.min) ||
                !parse_number(r.query.at("max"), &range.max))) {
    return error_response(400, "min and max are numbers");
  }
  if (st.ok() && !given) st = field_range(ex, s, paint, &range);
  std::string bytes;
  const bool danglings = r.query.count("danglings") && r.query.at("danglings") != "0";
  if (st.ok()) {
    st = render_tile(ex, s, paint, range.min, range.max, int(zoom), x, y, &bytes, danglings);
  }
  if (!st.ok()) return status_response(st);
  return {200, "image/png", std::move(bytes)};
}

Response Service::geo(Explorer& ex, const Request& r) {
  double x = 0, y = 0;
  if (!r.query.count("x") || !r.query.count("y") || !parse_number(r.query.at("x"), &x) ||
      !parse_number(r.query.at("y"), &y)) {
    return error_response(400, "geo takes x and y in metres");
  }
  GeoFrame frame;
  if (ex.units().geo.empty()) return error_response(404, "this database is not georeferenced");
  const Status st = GeoFrame::parse(ex.units().geo, &frame);
  if (!st.ok()) return status_response(st);
  double lon = 0, lat = 0;
  frame.to_geo(x, y, &lon, &lat);
  return {200, "application/json",
          "{\"x\": " + number(x) + ", \"y\": " + number(y) + ", \"lon\": " + number(lon) +
              ", \"lat\": " + number(lat) + "}\n"};
}

Response Service::export_vtu(Explorer& ex, const Request& r) {
  if (!r.query.count("box")) return error_response(400, "export takes box=X0,Y0,Z0,X1,Y1,Z1");
  const std::vector<std::string> words = split(r.query.at("box"), ',');
  ExportOptions o;
  bool ok = words.size() == 6;
  for (size_t i = 0; ok && i < 6; ++i) ok = parse_number(words[i], &o.box[i]);
  if (!ok) return error_response(400, "box is six numbers in metres: X0,Y0,Z0,X1,Y1,Z1");
  // How many elements first: a region past kMaxExportElements is for
  // weaver export.
  std::vector<std::string> count = {"range"};
  count.insert(count.end(), words.begin(), words.end());
  count.insert(count.end(), {"--units", "m"});
  const Response counted = run(ex, count, Request{});
  if (counted.status != 200) return counted;
  const std::string& out = counted.body;
  const size_t at = out.find("\"count\": ");
  const uint64_t n = at == std::string::npos ? 0 : std::strtoull(out.c_str() + at + 9, nullptr, 10);
  if (n == 0) return error_response(404, "no element shares a point with the box");
  if (n > kMaxExportElements) {
    return error_response(413, std::to_string(n) + " elements share a point with the box, more " +
                                   "than " + std::to_string(kMaxExportElements) +
                                   ": use weaver export --format vtu --box");
  }
  // Written by the exporter into a scratch directory of its own, opened,
  // and removed at once: the open file is streamed, never held whole.
  char dir[] = "/tmp/weaver-serve-XXXXXX";
  if (::mkdtemp(dir) == nullptr) return error_response(500, "cannot make a scratch directory");
  o.format = ExportFormat::kVtu;
  o.out = std::string(dir) + "/region.vtu";
  o.has_box = true;
  o.memory = memory_;
  ExportResult result;
  const Status st = export_mesh(db_, o, &result);
  std::shared_ptr<std::FILE> file(st.ok() ? std::fopen(o.out.c_str(), "rb") : nullptr,
                                  [](std::FILE* f) {
                                    if (f) std::fclose(f);
                                  });
  std::error_code ec;
  std::filesystem::remove_all(dir, ec);
  if (!st.ok()) return status_response(st);
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
