// The C++ library API (include/weaver/weaver.h) over the Explorer.
#include <weaver/weaver.h>

#include <algorithm>
#include <thread>

#include "query/explorer.h"
#include "query/shared_batch.h"

namespace weaver::api {
namespace {

constexpr int kMaxThreads = 256;

Point point_of(const Octant& o) { return {o.x, o.y, o.z}; }

bool check(const Status& st, std::string* error) {
  if (st.ok()) return true;
  *error = st.is_corruption() ? "corrupt data: " + st.message()
           : st.is_io_error() ? "I/O error: " + st.message()
                              : st.message();
  return false;
}

void copy_element(const MeshElement& e, Element* out) {
  out->id = e.id;
  out->corner = point_of(e.octant);
  out->level = e.octant.level;
  out->edge = octant_edge(e.octant);
  out->nodes = e.nodes;
  out->vp = e.vp, out->vs = e.vs, out->rho = e.rho;
}

void copy_node(const MeshNode& n, Node* out) {
  out->id = n.id;
  out->at = {n.c.x, n.c.y, n.c.z};
  out->kind = static_cast<NodeKind>(n.kind);
  out->anchor_count = n.anchor_count;
  out->anchors = n.anchors;
}

// One step of a cursor over a scan: moves on (after the first item), then
// hands out the item or records why the scan ended.
template <class Scan, class Fill>
bool step(Scan* scan, bool* started, bool* ok, std::string* error, Fill fill) {
  if (!*ok || scan == nullptr) return false;
  if (*started) scan->next();
  *started = true;
  if (!scan->valid()) return *ok = check(scan->status(), error), false;
  fill(*scan);
  return true;
}

}  // namespace

ElementCursor::ElementCursor(std::unique_ptr<weaver::ElementScan> scan, std::string* error)
    : scan_(std::move(scan)), error_(error) {}
ElementCursor::ElementCursor(ElementCursor&&) noexcept = default;
ElementCursor::~ElementCursor() = default;

bool ElementCursor::next(Element* out) {
  return step(scan_.get(), &started_, &ok_, error_,
              [&](const weaver::ElementScan& s) { copy_element(s.element(), out); });
}

bool ElementCursor::ok() const { return ok_; }

NodeCursor::NodeCursor(std::unique_ptr<weaver::NodeScan> scan, std::string* error)
    : scan_(std::move(scan)), error_(error) {}
NodeCursor::NodeCursor(NodeCursor&&) noexcept = default;
NodeCursor::~NodeCursor() = default;

bool NodeCursor::next(Node* out) {
  return step(scan_.get(), &started_, &ok_, error_,
              [&](const weaver::NodeScan& s) { copy_node(s.node(), out); });
}

bool NodeCursor::ok() const { return ok_; }

std::unique_ptr<MeshDatabase> MeshDatabase::open(const std::string& path, std::string* error,
                                                 uint64_t memory_bytes) {
  return open(path, error, memory_bytes, 1);
}

std::unique_ptr<MeshDatabase> MeshDatabase::open(const std::string& path, std::string* error,
                                                 uint64_t memory_bytes, int threads) {
  if (threads < 0 || threads > kMaxThreads) {
    *error = "threads must be 0 (one a core) to " + std::to_string(kMaxThreads) + ", not " +
             std::to_string(threads);
    return nullptr;
  }
  if (threads == 0) threads = int(std::max(1u, std::thread::hardware_concurrency()));
  std::unique_ptr<MeshDatabase> db(new MeshDatabase());
  if (!db->open_explorers(path, memory_bytes, threads, error)) return nullptr;
  return db;
}

// `threads` Explorers, the memory shared among them (as `weaver query`
// shares --memory among its threads).
bool MeshDatabase::open_explorers(const std::string& path, uint64_t memory_bytes, int threads,
                                  std::string* error) {
  const MemoryBudget each(std::max(memory_bytes / uint64_t(threads), MemoryBudget::kMinBytes));
  std::vector<Explorer*> shared;
  for (int i = 0; i < threads; ++i) {
    std::unique_ptr<Explorer>& e = i == 0 ? ex_ : helpers_.emplace_back();
    if (!check(Explorer::open(path, each, &e), error)) return false;
    shared.push_back(e.get());
  }
  batch_ = std::make_unique<SharedBatch>(std::move(shared));
  return true;
}

int MeshDatabase::threads() const { return 1 + int(helpers_.size()); }

MeshDatabase::~MeshDatabase() = default;

uint64_t MeshDatabase::element_count() const { return ex_->element_count(); }
uint64_t MeshDatabase::node_count() const { return ex_->node_count(); }
bool MeshDatabase::has_mesh() const { return ex_->has_nodes(); }
bool MeshDatabase::has_material() const { return ex_->mesh().has_material(); }

Units MeshDatabase::units() const { return {ex_->units().tick_m, ex_->units().origin_m}; }

bool MeshDatabase::locate(Point p, PointHit* out) { return locate(&p, 1, out); }

bool MeshDatabase::locate(const Point* p, size_t n, PointHit* out) {
  // Point and Coord are both three uint32_t; copied anyway, not aliased.
  std::vector<Coord> c(n);
  for (size_t i = 0; i < n; ++i) c[i] = {p[i].x, p[i].y, p[i].z};
  std::vector<weaver::PointHit> h(n);
  if (!check(batch_->locate(c.data(), n, h.data()), &error_)) return false;
  for (size_t i = 0; i < n; ++i) {
    out[i] = PointHit{};
    if (!h[i].inside) continue;
    out[i] = {
        true,    h[i].id, point_of(h[i].leaf), h[i].leaf.level, octant_edge(h[i].leaf), h[i].vp,
        h[i].vs, h[i].rho};
  }
  return true;
}

bool MeshDatabase::element(uint64_t id, Element* out) {
  MeshElement e;
  if (!check(ex_->element(id, &e), &error_)) return false;
  copy_element(e, out);
  return true;
}

bool MeshDatabase::node(uint64_t id, Node* out) {
  MeshNode n;
  if (!check(ex_->node(id, &n), &error_)) return false;
  copy_node(n, out);
  return true;
}

bool MeshDatabase::node_at(Point p, bool* found, uint64_t* id) {
  const Coord c{p.x, p.y, p.z};
  NodeHit h;
  if (!check(ex_->node_at_batch(&c, 1, &h), &error_)) return false;
  *found = h.found, *id = h.id;
  return true;
}

bool MeshDatabase::neighbors(uint64_t element, bool faces, bool edges, bool corners,
                             std::vector<Neighbor>* out) {
  const unsigned kinds = (faces ? 2u : 0u) | (edges ? 4u : 0u) | (corners ? 8u : 0u);
  std::vector<weaver::Neighbor> got;
  if (!check(ex_->neighbors(element, kinds, &got), &error_)) return false;
  out->clear();
  for (const weaver::Neighbor& n : got) out->push_back({n.dir.dx, n.dir.dy, n.dir.dz, n.id});
  return true;
}

bool MeshDatabase::node_elements(uint64_t node, std::vector<uint64_t>* out) {
  std::vector<NodeElement> got;
  if (!check(ex_->node_elements(node, &got), &error_)) return false;
  out->clear();
  for (const NodeElement& e : got) out->push_back(e.id);
  return true;
}

bool MeshDatabase::depends(uint64_t node, std::vector<uint64_t>* out) {
  std::vector<MeshNode> got;
  if (!check(ex_->depends(node, &got), &error_)) return false;
  out->clear();
  for (const MeshNode& n : got) out->push_back(n.id);
  return true;
}

ElementCursor MeshDatabase::elements(uint64_t first) {
  auto scan = std::make_unique<ElementScan>();
  ElementCursor c(nullptr, &error_);
  const Status st = scan->start(ex_->mesh(), first, has_mesh());
  if (!check(st, &error_)) {
    c.ok_ = false;
    return c;
  }
  c.scan_ = std::move(scan);
  return c;
}

NodeCursor MeshDatabase::nodes() {
  auto scan = std::make_unique<NodeScan>();
  NodeCursor c(nullptr, &error_);
  Status st = ex_->require_nodes();
  if (st.ok()) st = scan->start(ex_->mesh(), true);
  if (!check(st, &error_)) {
    c.ok_ = false;
    return c;
  }
  c.scan_ = std::move(scan);
  return c;
}

}  // namespace weaver::api
