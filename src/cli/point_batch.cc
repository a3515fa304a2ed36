#include "cli/point_batch.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <thread>
#include <vector>

#include "cli/point_line.h"
#include "cli/row_writer.h"
#include "query/shared_batch.h"
#include "util/huge_pages.h"
#include "util/interrupt.h"
#include "util/ordered_run.h"

namespace weaver::cli {
namespace {

// A coordinate that lies outside every mesh: the answer is "outside".
constexpr uint32_t kFar = UINT32_MAX;
static_assert(kFar == kTickLimit);

// Lines of a stream, read 64 KiB at a time (getline's per-line cost shows
// at a million lines a second; a larger buffer gains nothing, and one point
// asked through `weaver serve` would zero it).  A line is valid until the
// next call.  A line longer than the buffer is no point: it comes back as
// its first kMaxLine bytes, marked too long, and the rest of it is skipped
// unread into memory (a stream of /dev/zero is one such line, not an
// allocation without end).
class LineReader {
 public:
  static constexpr size_t kMaxLine = 64 << 10;
  explicit LineReader(std::FILE* in) : in_(in), buf_(kMaxLine) {}
  bool next(std::string_view* line, bool* too_long) {
    *too_long = false;
    for (;;) {
      const char* nl = static_cast<const char*>(std::memchr(&buf_[at_], '\n', len_ - at_));
      if (nl != nullptr) {
        *line = std::string_view(&buf_[at_], size_t(nl - &buf_[at_]));
        at_ = size_t(nl - buf_.data()) + 1;
        return true;
      }
      if (eof_) {
        if (at_ == len_) return false;
        *line = std::string_view(&buf_[at_], len_ - at_);  // the last line, unterminated
        at_ = len_;
        return true;
      }
      if (at_ == 0 && len_ == buf_.size()) {
        *line = std::string_view(buf_.data(), len_);
        *too_long = true;
        skip_line();
        return true;
      }
      refill();
    }
  }

 private:
  // Keeps the partial line at the front and reads more after it.
  void refill() {
    std::memmove(buf_.data(), &buf_[at_], len_ - at_);
    len_ -= at_, at_ = 0;
    const size_t n = std::fread(&buf_[len_], 1, buf_.size() - len_, in_);
    len_ += n;
    eof_ = n == 0;
  }
  // Drops the rest of a long line: read on to its end a byte at a time
  // through stdio's buffer, none of it kept.  The line's first bytes stay
  // in the buffer for the caller, and are dropped at the next call.
  void skip_line() {
    for (int c; (c = getc_unlocked(in_)) != '\n';) {
      if (c == EOF) {
        eof_ = true;
        break;
      }
    }
    at_ = len_;
  }

  std::FILE* in_;
  std::vector<char> buf_;
  size_t at_ = 0, len_ = 0;
  bool eof_ = false;
};

// The Explorer asked, then its helpers.
std::vector<Explorer*> explorers(Explorer& ex, const PointBatchOptions& o) {
  std::vector<Explorer*> all = {&ex};
  all.insert(all.end(), o.helpers.begin(), o.helpers.end());
  return all;
}

class BatchRunner {
 public:
  BatchRunner(Explorer& ex, const PointBatchOptions& o, std::FILE* out)
      : ex_(ex), o_(o), out_(out), w_(o.mode, o.one), shared_(explorers(ex, o)) {}

  void header() {
    std::vector<const char*> c = {"x", "y", "z", "status"};
    if (o_.query == PointQuery::kNodeAt) {
      c.insert(c.end(), {"node", "kind"});
    } else if (o_.query == PointQuery::kMaterial) {
      c.insert(c.end(), {"element", "vp", "vs", "rho"});
    } else {
      c.insert(c.end(), {"element", "level", "edge", "corner_x", "corner_y", "corner_z"});
      if (ex_.mesh().has_material()) c.insert(c.end(), {"vp", "vs", "rho"});
    }
    if (o_.query != PointQuery::kNodeAt && ex_.mesh().has_q()) c.insert(c.end(), {"qp", "qs"});
    w_.header(c);
    answer_columns_ = int(c.size()) - 4;  // what follows x, y, z and the status
  }

  // Parses one line: false when it is malformed (*why says how).
  bool add(const char* s, size_t n, std::string* why) {
    if (points_.size() == points_.capacity()) grow();
    double v[3];
    if (!parse_point_line(s, n, o_.metres, v, why)) return false;
    Coord c;
    uint32_t* axis[3] = {&c.x, &c.y, &c.z};
    for (int a = 0; a < 3; ++a) *axis[a] = to_tick(v[a], a);
    points_.push_back(c);
    if (o_.metres) values_.push_back({v[0], v[1], v[2]});
    bad_.push_back(false);
    return true;
  }
  // Room for more points: a batch's arrays grow by fourfold steps up to the
  // batch's size, so that one point (a request of `weaver serve`) does not
  // reserve, and fault in huge pages for, a million.
  void grow() {
    const size_t n = std::min(limit(), std::max<size_t>(4096, 4 * points_.size()));
    reserve_huge(points_, n);
    if (o_.metres) reserve_huge(values_, n);
    reserve_huge(hits_, o_.query == PointQuery::kNodeAt ? 0 : n);
    reserve_huge(nodes_, o_.query == PointQuery::kNodeAt ? n : 0);
  }
  void add_bad() {
    if (points_.size() == points_.capacity()) grow();
    points_.push_back({kFar, kFar, kFar});
    if (o_.metres) values_.push_back({NAN, NAN, NAN});
    bad_.push_back(true);
  }
  size_t size() const { return points_.size(); }
  // Points answered at a time.  The batch holds every buffer (the Explorers only walk its runs), so
  // the shares all of them set aside for a batch are its.
  size_t limit() const {
    if (o_.batch_points > 0) return o_.batch_points;
    uint64_t bytes = ex_.batch_bytes();
    for (const Explorer* e : o_.helpers) bytes += e->batch_bytes();
    return size_t(std::clamp<uint64_t>(bytes / kBatchPointBytes, 4096, 1 << 22));
  }

  // Answers the points held and writes their rows.
  Status answer(PointBatchResult* r) {
    const size_t n = points_.size();
    const size_t parts = shared_.parts(n);
    WEAVER_RETURN_IF_ERROR(look_up(n));
    WEAVER_RETURN_IF_ERROR(write_rows(n, parts, &r->missed));
    r->points += n;
    points_.clear(), values_.clear(), bad_.clear();
    return Status::Ok();
  }

  Status finish() {
    w_.close_document();
    return w_.flush(out_);
  }

 private:
  static constexpr size_t kSlice = 32768;  // rows formatted, then written

  // Rows [lo, hi) of a batch, formatted into w (one of writers_, this
  // slice object's for good, so its buffer keeps its room).
  struct RowSlice {
    RowWriter* w = nullptr;
    size_t lo = 0, hi = 0;
    uint64_t missed = 0;
  };

  // The batch's answers, shared among the Explorers (query/shared_batch.h).
  // The answer arrays only grow: their entries are all written each time.
  Status look_up(size_t n) {
    if (o_.query == PointQuery::kNodeAt) {
      if (nodes_.size() < n) nodes_.resize(n);
      return shared_.node_at(points_.data(), n, nodes_.data());
    }
    if (hits_.size() < n) hits_.resize(n);
    return shared_.locate(points_.data(), n, hits_.data());
  }

  // The rows in slices: `parts` slices formatted at once, a thread each,
  // then written in input order.
  Status write_rows(size_t n, size_t parts, uint64_t* missed) {
    if (parts == 1) {
      for (size_t lo = 0; lo < n; lo += kSlice) {
        format_rows(w_, lo, std::min(n, lo + kSlice), missed);
        WEAVER_RETURN_IF_ERROR(w_.flush(out_));
      }
      return Status::Ok();
    }
    WEAVER_RETURN_IF_ERROR(w_.flush(out_));  // the header, before the rows
    // Slices are formatted on every thread and written in order by one at a
    // time, while the others format the next: the writes took a fifth of
    // the time of a million rows when every thread waited for them.
    const size_t in_flight = 2 * parts;
    while (writers_.size() < in_flight) writers_.push_back(w_.continuation(0));
    size_t next = 0, claimed = 0;
    Status st;
    OrderedRun<RowSlice> run(
        in_flight,
        [&](RowSlice* s) {
          if (next == n) return false;
          if (s->w == nullptr) s->w = &writers_[claimed++];
          s->lo = next, s->hi = next = std::min(n, next + kSlice);
          s->w->resume(w_.rows() + s->lo);
          return true;
        },
        [&](int, RowSlice* s) { format_rows(*s->w, s->lo, s->hi, &s->missed); },
        [&](RowSlice* s) {
          *missed += s->missed;
          s->missed = 0;
          st = s->w->flush(out_);
          return st.ok();
        });
    run.go(int(parts));
    w_.count_rows(n);
    return st;
  }

  uint32_t to_tick(double v, int axis) const {
    const Units& u = ex_.units();
    const double t = o_.metres ? std::floor((v - u.origin_m[axis]) / u.tick_m) : v;
    return t >= 0 && t < 4294967295.0 ? uint32_t(t) : kFar;
  }

  double length(uint64_t ticks) const { return double(ticks) * ex_.units().tick_m; }
  double position(uint32_t tick, int axis) const {
    return ex_.units().origin_m[axis] + double(tick) * ex_.units().tick_m;
  }

  void format_rows(RowWriter& w, size_t lo, size_t hi, uint64_t* missed_out) const {
    const bool node = o_.query == PointQuery::kNodeAt;
    uint64_t missed = 0;
    for (size_t i = lo; i < hi; ++i) {
      RowCursor c(w.row(), w.style());
      const bool bad = bad_[i];
      for (int a = 0; a < 3; ++a) {
        if (bad) {
          c.null();
        } else if (o_.metres) {
          c.number(values_[i][a]);
        } else {
          c.number(uint64_t(a == 0 ? points_[i].x : a == 1 ? points_[i].y : points_[i].z));
        }
      }
      const bool found = !bad && (node ? nodes_[i].found : hits_[i].inside);
      c.text(bad                      ? "bad"
             : found                  ? (node ? "node" : "inside")
             : node                   ? "none"
             : ex_.in_air(points_[i]) ? "air"
                                      : "outside");
      missed += !bad && !found;
      if (!found) {
        for (int k = 0; k < answer_columns_; ++k) c.null();
      } else if (node) {
        c.number(nodes_[i].id);
        c.text(node_kind_name(nodes_[i].kind));
      } else {
        write_hit(c, hits_[i]);
      }
      w.done(c.end());
    }
    *missed_out += missed;
  }

  void write_hit(RowCursor& c, const PointHit& h) const {
    c.number(h.id);
    if (o_.query == PointQuery::kLocate) {
      c.number(uint64_t(h.leaf.level));
      const uint32_t corner[3] = {h.leaf.x, h.leaf.y, h.leaf.z};
      if (o_.metres) {
        c.number(length(octant_edge(h.leaf)));
        for (int a = 0; a < 3; ++a) c.number(position(corner[a], a));
      } else {
        c.number(uint64_t(octant_edge(h.leaf)));
        for (int a = 0; a < 3; ++a) c.number(uint64_t(corner[a]));
      }
      if (!ex_.mesh().has_material()) return;
    }
    c.number(h.vp), c.number(h.vs), c.number(h.rho);
    if (ex_.mesh().has_q()) c.number(h.qp), c.number(h.qs);
  }

  Explorer& ex_;
  const PointBatchOptions& o_;
  std::FILE* out_;
  RowWriter w_;
  std::vector<Coord> points_;
  std::vector<std::array<double, 3>> values_;
  std::vector<bool> bad_;
  std::vector<RowWriter> writers_;  // slices' rows, for a batch shared among threads
  std::vector<PointHit> hits_;
  std::vector<NodeHit> nodes_;
  SharedBatch shared_;
  int answer_columns_ = 0;  // a row's fields after its status: empty when nothing was found
};

}  // namespace

Status run_point_batch(Explorer& ex, std::FILE* in, const std::string& name,
                       const PointBatchOptions& o, std::FILE* out, std::FILE* err,
                       PointBatchResult* result) {
  *result = PointBatchResult{};
  if (o.query == PointQuery::kNodeAt) WEAVER_RETURN_IF_ERROR(ex.require_nodes());
  if (o.query == PointQuery::kMaterial && !ex.mesh().has_material()) {
    return Status::NotFound("this mesh has no material (it was not built from a model)");
  }
  BatchRunner batch(ex, o, out);
  batch.header();
  LineReader lines(in);
  uint64_t line_no = 0;
  Status st;
  std::string why;
  bool too_long = false;
  for (std::string_view text; st.ok() && lines.next(&text, &too_long);) {
    if (interrupted()) {
      st = Status::Busy("interrupted at line " + std::to_string(line_no + 1) + " of " + name);
      break;
    }
    ++line_no;
    const char* line = text.data();
    size_t len = text.size();
    while (len > 0 && line[len - 1] == '\r') --len;
    size_t first = 0;
    while (first < len && (line[first] == ' ' || line[first] == '\t')) ++first;
    if (!too_long && (first == len || line[first] == '#')) continue;
    if (too_long) why = "a line longer than " + std::to_string(LineReader::kMaxLine >> 10) + " KiB";
    if (too_long || !batch.add(line + first, len - first, &why)) {
      std::fprintf(err, "%s:%llu: %s\n", name.c_str(), (unsigned long long)line_no, why.c_str());
      batch.add_bad();
      ++result->bad_lines;
    }
    if (batch.size() >= batch.limit()) st = batch.answer(result);
  }
  const bool read_error = std::ferror(in);
  if (st.ok()) st = batch.answer(result);
  if (st.ok()) st = batch.finish();
  if (st.ok() && read_error) st = Status::IOError("reading " + name + ": " + std::strerror(errno));
  return st;
}

}  // namespace weaver::cli
