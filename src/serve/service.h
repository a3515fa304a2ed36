// What `weaver serve` answers: the page, the JSON API and the map tiles of
// one database, read-only.  Each request runs on one snapshot: a worker
// thread keeps its own open Explorer and opens the database again when its
// MANIFEST has changed (a writer committed), so a client never sees a mixed
// state and sees the new one from its next request on.
//
// Routes (JSON answers are those of `weaver query ... --format json`):
//   GET  /, /page.css, /page.js    the page (serve/page.cc)
//   GET  /api/stat                 the mesh: counts, units, extents, fields
//   GET  /api/locate?x=&y=&z=[&units=m|ticks][&geo=1]
//   POST /api/points[?query=locate|material|node-at][&units=][&geo=1]
//                                  points as text lines or a JSON array
//   GET  /api/element/ID, /api/node/ID, /api/neighbors/ID[?kinds=all]
//   GET  /api/node-elements/ID, /api/depends/ID
//   GET  /api/range?box=X0,Y0,Z0,X1,Y1,Z1[&units=]   the count
//   GET  /api/range?box=...&list=1[&limit=N][&from=ID]  the elements, a page
//                                  of at most N (kMaxListed) streamed as
//                                  they are found: {"elements": [...],
//                                  "count", "listed", "truncated", "next"}
//   GET  /api/section/AXIS/POSITION?color=F[&summary=S]   the section's
//                                  extent, the colour range its tiles share
//                                  and what a pixel of many elements shows
//   GET  /api/tile/AXIS/POSITION/ZOOM/X/Y.png?color=F[&summary=S][&min=&max=]
//                                  [&danglings=1]
//                                  (S: min, max, mean or centre; serve/tiles.h)
//   GET  /api/geo?x=&y=            metres in the frame as WGS84 lon, lat
//                                  (a georeferenced mesh only)
//   GET  /api/export.vtu?box=X0,Y0,Z0,X1,Y1,Z1   (metres) the elements that
//                                  share a point with the box, as `weaver
//                                  export --format vtu --box` writes them
//                                  (at most kMaxExportElements)
#pragma once

#include <sys/types.h>

#include <cstdio>
#include <ctime>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "query/explorer.h"
#include "serve/api_query.h"
#include "serve/guard.h"
#include "serve/http.h"
#include "serve/tiles.h"
#include "util/memory_budget.h"

namespace weaver::serve {

// Runs one query of `weaver query` as q asks it, its answer as JSON, on ex,
// with helpers (more Explorers on the same state, which a batch of points
// shares its work with), reading a batch's points from points and printing
// to out: the exit status, and the first kErrorHeld bytes of what it printed
// to stderr.  The command line supplies it (cli/serve_queries.h).
// What a query's errors keep: the first of them (a batch of a million bad
// lines writes a million).
inline constexpr size_t kErrorHeld = 4096;
using QueryRunner =
    std::function<int(Explorer& ex, const std::vector<Explorer*>& helpers, const ApiQuery& q,
                      std::FILE* points, std::FILE* out, std::string* err)>;

// Which committed state a reader opened: its MANIFEST's inode and change
// time (a commit renames a new MANIFEST into place).
struct StateStamp {
  ino_t ino = 0;
  timespec ctime{};
  bool operator==(const StateStamp& o) const {
    return ino == o.ino && ctime.tv_sec == o.ctime.tv_sec && ctime.tv_nsec == o.ctime.tv_nsec;
  }
};

class Service {
 public:
  // memory: each Explorer's (a worker's, the helper's); directories: what
  // the tables' leaf directories take, built once for each committed state
  // and shared by every Explorer of it.
  // lane: the memory one batch of points at a time may hold, in points
  // (0: none; every batch within its Explorer's share).
  Service(std::string db, MemoryBudget memory, uint64_t directories, QueryRunner query,
          size_t lane_points = 0)
      : db_(std::move(db)),
        memory_(memory),
        directories_(directories),
        query_(std::move(query)),
        lane_points_(lane_points) {}

  // Checks that the database opens: the error a user sees before the
  // server starts.
  Status check();
  // Opens this thread's snapshot and readies its tables for lookups (the
  // B+trees' leaf directories), so that a thread's first request is not its
  // slowest (2 s for a tile of the 2 Hz basin otherwise).
  void warm();
  // Who may call (serve/guard.h): set once the server listens.
  void set_callers(CallerPolicy p) { callers_ = std::move(p); }
  // Where a region's vtu is written before it is sent (default: the
  // database's directory, whose next writer removes what a crash left).
  void set_scratch(std::string dir) { scratch_ = std::move(dir); }
  Response handle(const Request& r);

 private:
  // This thread's Explorer on the newest committed state.
  Status explorer(Explorer** out);
  Response api(const Request& r, Explorer& ex);
  // The query's answer held whole: for the questions of one thing.
  Response run(Explorer& ex, const ApiQuery& q);
  // A batch of points from r's body, its answer streamed as it is printed
  // (a million points are about 130 MB of JSON).
  Response run_batch(Explorer& ex, const ApiQuery& q, const Request& r);
  // A page of a range's elements, streamed as they are found.
  Response run_list(Explorer& ex, const ApiQuery& q);
  // The colour range of a section's paint: found once a committed state
  // and shared by the workers (it reads the 65536 pixels of zoom 0).
  Status shared_range(Explorer& ex, const Section& s, const Paint& paint, FieldRange* range);
  Response stat(Explorer& ex);
  Response section(Explorer& ex, const std::vector<std::string>& parts, const Request& r);
  Response tile(Explorer& ex, const std::vector<std::string>& parts, const Request& r);
  Response export_vtu(const Request& r);
  Response geo(Explorer& ex, const Request& r);

  // The helper Explorer on this thread's snapshot, if no other batch has
  // it (*lock then holds it); null otherwise.
  Explorer* helper(std::unique_lock<std::mutex>* lock);
  // Gives ex's tables the leaf directories of the state `state`, built by
  // the first Explorer of that state to ask.
  void share_directories(Explorer& ex, const StateStamp& state);

  std::string db_;
  std::string scratch_;  // empty: db_
  CallerPolicy callers_;
  MemoryBudget memory_;
  uint64_t directories_;
  QueryRunner query_;
  // The batch lane: a batch of points that finds it free answers this many
  // points at a time, not its Explorer's batch (far fewer page reads for a
  // million random points: each batch reads about one leaf page a point).
  size_t lane_points_;
  std::mutex lane_mu_;
  // The leaf directories of one committed state (a table's is null until
  // built, or when it does not fit).
  std::mutex directories_mu_;
  StateStamp directories_state_;
  std::shared_ptr<const LeafDirectory> octant_directory_, node_directory_, aggregate_directory_;
  // One more Explorer, which a batch of points borrows to answer half of
  // its points on a second thread; opened on the first batch, and again
  // when the state it reads is no longer a worker's.
  std::mutex helper_mu_;
  std::unique_ptr<Explorer> helper_;
  StateStamp helper_state_;
  // The colour ranges found in the state ranges_state_, by section and paint.
  std::mutex ranges_mu_;
  StateStamp ranges_state_;
  std::map<std::string, FieldRange> ranges_;
};

// range?list=1: at most this many elements a page (about 100 MB of JSON);
// a request may ask for fewer with limit=N.
inline constexpr uint64_t kMaxListed = 1000000;
// The colour ranges remembered at once (a range is 24 bytes and its key a
// few more; past this many the memory starts again).
inline constexpr size_t kMaxRanges = 4096;

// A region downloaded as vtu is written to a scratch file first (in a
// "tmp-serve-*" directory inside the database, which the next writer
// removes if the server dies), then streamed: at most this many elements
// (about 100 MB of vtu); larger ones are for `weaver export`.
inline constexpr uint64_t kMaxExportElements = 1000000;

// The page (/), its style (/page.css) and its script (/page.js); nothing
// fetched from elsewhere.
extern const char kPage[];
extern const char kPageCss[];
extern const char kPageJs[];

}  // namespace weaver::serve
