#include "query/explorer.h"

#include <algorithm>
#include <cmath>

#include "util/huge_pages.h"
#include "util/radix_sort.h"

namespace weaver {
namespace {

// Batches smaller than this ask the tables key by key (LeafWindow's sparse
// mode): a few questions land in different leaves, and decoding a whole
// leaf for each costs more than two descents.
constexpr size_t kDenseBatch = 64;
// A larger batch starts dense, and is watched a window of points at a time:
// when a window needed a page decoded for fewer than 8 points on average
// (points spread over a huge table: a map tile of a whole section, a
// million random points in a billion leaves), decoding whole pages costs
// more than two descents a point (175 against 50 ms for a zoom-0 tile of
// the 2 Hz basin), and the rest of the batch is asked key by key.
constexpr size_t kDensityWindow = 1024;
constexpr size_t kFirstWindow = kDensityWindow / 16;

// The watch over one batch's lookups in a window: dense at first (unless
// the batch is small), key by key once a window of points proves sparse.
// The first window (kFirstWindow) is short: a sparse batch then decodes at
// most 64 whole pages before it goes key by key, not up to 1024 (at 2 Hz a
// page holds about 3900 leaves, and decoding one costs about 80
// instructions a leaf: the first 1024 of a million random points decoded
// 440 pages, a tenth of the instructions of 200K points on one thread).  A
// dense batch (sorted points many to a page) finds its first 64 points in
// one or two pages and stays dense.
class DensityWatch {
 public:
  DensityWatch(LeafWindow& w, size_t n) : w_(w), before_(w.decodes()) {
    w.set_sparse(n < kDenseBatch);
  }
  // Before the k-th lookup of the batch.
  void at(size_t k) {
    const size_t window = k < kFirstWindow ? kFirstWindow : kDensityWindow;
    const size_t from = k < kFirstWindow ? 0 : kFirstWindow;
    if ((k - from) % window != window - 1 || w_.sparse()) return;
    const uint64_t decodes = w_.decodes();
    if (decodes - before_ > window / 8) w_.set_sparse(true, true);
    before_ = decodes;
  }

 private:
  LeafWindow& w_;
  uint64_t before_;
};

// The key of the octant of `level` (below 20) that holds pixel c.
uint64_t octant_key_at(Coord c, int level) { return octant_key_ancestor(pixel_key(c), level); }

}  // namespace

bool Explorer::load_ground() {
  if (ground_state_ == 0) {
    ground_state_ = -1;
    if (mesh_->has_ground() &&
        ground_of_metadata(mesh_->octants().options().metadata, 64ull << 20, &surface_, &ground_)
            .ok()) {
      ground_state_ = 1;
    }
  }
  return ground_state_ == 1;
}

double Explorer::ground_at(Coord p) {
  if (!load_ground()) return NAN;
  const Units& u = mesh_->units();
  return ground_.ground_at(u.origin_m[0] + u.tick_m * p.x, u.origin_m[1] + u.tick_m * p.y);
}

bool Explorer::in_air(Coord p) {
  if (!load_ground()) return false;
  const Units& u = mesh_->units();
  const double ground = ground_at(p);
  const double elevation = ground_.top_elevation - (u.origin_m[2] + u.tick_m * p.z);
  if (!(elevation > ground)) return false;
  // Above the ground, and over it: an element holds the point a tick below
  // the ground in the same column (else the point is beside the domain).
  const double below = std::ceil((ground_.top_elevation - ground - u.origin_m[2]) / u.tick_m) + 1;
  if (!(below >= 0 && below < double(kRootEdge))) return false;
  PointHit h;
  return locate({p.x, p.y, uint32_t(below)}, &h).ok() && h.inside;
}

Status Explorer::open(const std::string& db_dir, MemoryBudget memory,
                      std::unique_ptr<Explorer>* out) {
  const ExplorerMemory shares(memory);
  std::unique_ptr<Explorer> e(new Explorer());
  WEAVER_RETURN_IF_ERROR(Mesh::open(db_dir, shares.octant_pool, shares.node_pool, &e->mesh_, true));
  e->mesh_->octants().set_directory_budget(shares.octant_directory);
  if (e->mesh_->has_nodes()) e->mesh_->nodes().set_directory_budget(shares.node_directory);
  e->octant_window_ = std::make_unique<LeafWindow>(e->mesh_->octants(), true);
  if (e->mesh_->has_nodes()) {
    e->node_window_ = std::make_unique<LeafWindow>(e->mesh_->nodes(), true);
  }
  if (e->mesh_->has_aggregates()) {
    BTree& t = e->mesh_->aggregates();
    WEAVER_RETURN_IF_ERROR(AggregateLayout::of_table(t, &e->aggregate_layout_));
    e->aggregate_window_ = std::make_unique<LeafWindow>(t, true);
    e->aggregate_finest_ = weaver::aggregate_finest(t);
  }
  e->batch_bytes_ = shares.batch;
  *out = std::move(e);
  return Status::Ok();
}

Status Explorer::locate(Coord p, PointHit* out) { return locate_batch(&p, 1, out); }

template <typename Valid, typename KeyOf>
void Explorer::key_points(const Coord* p, size_t n, Valid valid, KeyOf key_of,
                          std::vector<KeyedPoint>* order) {
  order->clear();
  reserve_huge(*order, n);
  for (size_t i = 0; i < n; ++i) {
    if (valid(p[i])) order->push_back({key_of(p[i]), i});
  }
}

template <typename Hit, typename Valid, typename KeyOf>
void Explorer::sort_points(const Coord* p, size_t n, Hit* out, Valid valid, KeyOf key_of) {
  std::fill(out, out + n, Hit{});
  key_points(p, n, valid, key_of, &order_);
  reserve_huge(scratch_, n);
  radix_sort_by(order_, scratch_, [](const KeyedPoint& k) { return k.first; });
}

void Explorer::key_batch(const Coord* p, size_t n, bool nodes, std::vector<KeyedPoint>* order) {
  if (nodes) return key_points(p, n, node_is_valid, node_key, order);
  key_points(p, n, pixel_is_valid, pixel_key, order);
}

Status Explorer::locate_batch(const Coord* p, size_t n, PointHit* out) {
  sort_points(p, n, out, pixel_is_valid, pixel_key);
  return locate_sorted(order_.data(), order_.size(), out);
}

Status Explorer::locate_sorted(const KeyedPoint* order, size_t n, PointHit* out) {
  DensityWatch density(*octant_window_, n);
  LeafWindow::Floor f;
  MeshElement m;
  // The walk reads only the sorted pairs: the points themselves, in input
  // order, would cost a cache miss each.  The answers are written in input
  // order, a cache miss each: asked for a few points ahead, they overlap.
  constexpr size_t kAhead = 16;
  for (size_t k = 0; k < n; ++k) {
    const auto [key, i] = order[k];
    if (k + kAhead < n) __builtin_prefetch(&out[order[k + kAhead].second], 1);
    density.at(k);
    WEAVER_RETURN_IF_ERROR(octant_window_->floor(key, &f));
    // The floor leaf holds the pixel if the pixel's key is in its subtree;
    // if not, the pixel is in a hole of the domain.
    if (!f.found || key >= octant_key_subtree_end(f.key)) continue;
    PointHit& h = out[i];
    h.inside = true;
    h.id = f.rank;
    h.leaf = octant_from_key(f.key);
    mesh_->fill_material(f.payload, &m);
    h.vp = m.vp, h.vs = m.vs, h.rho = m.rho, h.qp = m.qp, h.qs = m.qs;
  }
  return Status::Ok();
}

Status Explorer::aggregate_batch(const Coord* p, size_t n, int level, AggregateHit* out) {
  if (level < 0 || level > aggregate_finest_) {
    return Status::InvalidArgument("the aggregate table has no level " + std::to_string(level));
  }
  sort_points(p, n, out, pixel_is_valid, [level](Coord c) { return octant_key_at(c, level); });
  DensityWatch density(*aggregate_window_, n);
  uint64_t last = UINT64_MAX;
  const std::byte* payload = nullptr;
  bool found = false;
  for (size_t k = 0; k < order_.size(); ++k) {
    const auto [key, i] = order_[k];
    density.at(k);
    // Points of one pixel's octant come together: one lookup serves them.
    if (key != last) WEAVER_RETURN_IF_ERROR(aggregate_window_->get(key, &payload, &found));
    last = key;
    if (!found) continue;
    out[i].found = true;
    aggregate_layout_.decode(payload, &out[i].a);
  }
  return Status::Ok();
}

Status Explorer::summarise_batch(const Coord* p, size_t n, int level, uint64_t max_leaves,
                                 AggregateHit* out) {
  if (level < 0 || level >= kMaxLevel) return Status::InvalidArgument("no octants inside level 20");
  sort_points(p, n, out, pixel_is_valid, [level](Coord c) { return octant_key_at(c, level); });
  BTree& octants = mesh_->octants();
  const LeafFields fields(octants);
  BTreeCursor c;
  uint64_t read = 0, last = UINT64_MAX, skipped = 0;
  bool started = false;
  AggregateHit hit;
  float values[5] = {};
  for (const auto& [key, i] : order_) {
    if (key != last && read < max_leaves) {
      last = key;
      // The first leaf at or past key: where the cursor stands, or further
      // on in the leaf page it holds, else found by a search.
      if (!started || (c.valid() && c.key() < key && !c.skip_in_leaf(key - 1, &skipped))) {
        WEAVER_RETURN_IF_ERROR(octants.seek_cursor(key, &c));
        started = true;
      }
      SummaryBuilder sum;
      const uint64_t end = octant_key_subtree_end(key);
      // A leaf with the octant's own key is the octant: nothing inside.
      const bool leaf = c.valid() && c.key() == key;
      for (; !leaf && c.valid() && c.key() < end; ++read) {
        fields.read(c.payload(), values);
        sum.add_leaf(octant_key_level(c.key()), values, fields.count());
        WEAVER_RETURN_IF_ERROR(c.next());
      }
      hit.found = sum.leaves() > 0;
      if (hit.found) hit.a = sum.result(fields.count());
    } else if (key != last) {
      break;  // past the budget: the rest stay not found
    }
    out[i] = hit;
  }
  return Status::Ok();
}

Status Explorer::require_nodes() const {
  return has_nodes() ? Status::Ok() : Status::NotFound("no mesh yet (run 'weaver extract' first)");
}

Status Explorer::node_at_batch(const Coord* p, size_t n, NodeHit* out) {
  sort_points(p, n, out, node_is_valid, node_key);
  return node_at_sorted(order_.data(), order_.size(), out);
}

Status Explorer::node_at_sorted(const KeyedPoint* order, size_t n, NodeHit* out) {
  WEAVER_RETURN_IF_ERROR(require_nodes());
  node_window_->set_sparse(n < kDenseBatch);
  LeafWindow::Floor f;
  for (size_t k = 0; k < n; ++k) {
    const auto [key, i] = order[k];
    WEAVER_RETURN_IF_ERROR(node_window_->floor(key, &f));
    if (!f.found || f.key != key) continue;
    const uint8_t kind = static_cast<uint8_t>(f.payload[0]);
    if (kind > 2) return Status::Corruption(mesh_->nodes().file_name() + ": bad node kind");
    out[i] = {true, f.rank, static_cast<NodeKind>(kind)};
  }
  return Status::Ok();
}

Status Explorer::check_node(uint64_t id) const {
  WEAVER_RETURN_IF_ERROR(require_nodes());
  if (id < node_count()) return Status::Ok();
  return Status::InvalidArgument("node " + std::to_string(id) + " does not exist (" +
                                 std::to_string(node_count()) + " nodes)");
}

Status Explorer::element(uint64_t id, MeshElement* out) { return mesh_->element(id, true, out); }

Status Explorer::node(uint64_t id, MeshNode* out) {
  WEAVER_RETURN_IF_ERROR(check_node(id));
  return mesh_->node(id, true, out);
}

}  // namespace weaver
