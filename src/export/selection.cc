#include "export/selection.h"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <vector>

#include "mesh/octant_query.h"
#include "sort/external_sort.h"
#include "storage/file.h"
#include "util/radix_sort.h"

namespace weaver {

namespace {

// The elements of ids [first, end) that sel keeps.
Status scan_ids(Mesh& mesh, const Selection& sel, uint64_t first, uint64_t end, bool with_nodes,
                const std::function<Status(MeshElement&)>& fn) {
  ElementScan scan;
  WEAVER_RETURN_IF_ERROR(scan.start(mesh, first, false));
  std::vector<MeshElement> kept;
  std::vector<Octant> octants;
  std::vector<std::array<uint64_t, 8>> ids;
  CornerBatch corners;
  auto flush = [&]() -> Status {
    if (with_nodes) {
      octants.clear();
      for (const MeshElement& e : kept) octants.push_back(e.octant);
      WEAVER_RETURN_IF_ERROR(corners.resolve(mesh.nodes(), octants, &ids));
    }
    for (size_t i = 0; i < kept.size(); ++i) {
      if (with_nodes) kept[i].nodes = ids[i];
      WEAVER_RETURN_IF_ERROR(fn(kept[i]));
    }
    kept.clear();
    return Status::Ok();
  };
  for (; scan.valid() && scan.element().id < end; scan.next()) {
    bool keep = false;
    WEAVER_RETURN_IF_ERROR(sel.keeps(scan.element().id, scan.element().octant, &keep));
    if (!keep) continue;
    kept.push_back(scan.element());
    if (kept.size() == 4096) WEAVER_RETURN_IF_ERROR(flush());
  }
  WEAVER_RETURN_IF_ERROR(scan.status());
  return flush();
}

// sel's box as the pixels a leaf sharing a point with it holds: a leaf
// [c, c + s) touches [lo, hi] (bounds included) when c <= hi and
// c + s >= lo, that is when it holds a pixel of [lo - 1, hi].
TickBox touching_pixels(const Selection& sel) {
  const auto below = [](uint32_t v) { return v > 0 ? v - 1 : 0; };
  return {{below(sel.lo.x), below(sel.lo.y), below(sel.lo.z)}, sel.hi};
}

}  // namespace

Status scan_selected(Mesh& mesh, const Selection& sel, bool with_nodes,
                     const std::function<Status(MeshElement&)>& fn) {
  if (!sel.has_box) return scan_ids(mesh, sel, sel.first, sel.end, with_nodes, fn);
  return range_runs(mesh.octants(), touching_pixels(sel), [&](uint64_t first, uint64_t end) {
    first = std::max(first, sel.first), end = std::min(end, sel.end);
    return first < end ? scan_ids(mesh, sel, first, end, with_nodes, fn) : Status::Ok();
  });
}

Status count_box_elements(Mesh& mesh, const Selection& sel, uint64_t* count) {
  return range_query(mesh.octants(), touching_pixels(sel), count, nullptr);
}

namespace {

// Adds node `id` to `out` with its anchors, and theirs where they dangle
// too: next to holes in the domain finer than the leaves' parents, an
// anchor can (docs/pipeline.md, extract), and a part that holds a dangling node must
// hold all the nodes its value follows from.  Where the leaves fill their
// parents every anchor is anchored, and this costs a kind lookup an anchor.
// Each node's tag is its kind, so that the node set counts its dangling.
Status add_with_anchors(Mesh& mesh, uint64_t id, ExternalSorter& out) {
  MeshNode n;
  WEAVER_RETURN_IF_ERROR(mesh.node(id, true, &n));
  WEAVER_RETURN_IF_ERROR(out.add({id, uint64_t(n.kind)}));
  std::vector<uint64_t> todo(n.anchors.begin(), n.anchors.begin() + n.anchor_count);
  while (!todo.empty()) {
    const uint64_t a = todo.back();
    todo.pop_back();
    MeshNode m;  // an anchored node has no anchors to look up
    WEAVER_RETURN_IF_ERROR(mesh.node(a, true, &m));
    WEAVER_RETURN_IF_ERROR(out.add({a, uint64_t(m.kind)}));
    todo.insert(todo.end(), m.anchors.begin(), m.anchors.begin() + m.anchor_count);
  }
  return Status::Ok();
}

}  // namespace

Status LocalNodes::build(Mesh& mesh, const Selection& sel, bool with_anchors,
                         const std::string& scratch_dir, uint64_t memory) {
  identity_ = sel.whole();
  if (identity_) {
    nodes_ = mesh.node_count();
    elements_ = mesh.element_count();
    return Status::Ok();
  }
  ::mkdir(scratch_dir.c_str(), 0755);
  // The corners of the selected elements, sorted; then, with the anchors
  // of those that dangle (one lookup a distinct node and an anchor), sorted
  // again.
  // A node is a corner of up to 8 elements, mostly near in Z-order: each
  // batch of corners goes to the sorter without its repeats.  The batch and
  // the sorter (and the radix sort's other buffer) share a quarter of the memory.
  ExternalSorter corners(scratch_dir + "/corners", memory / 8);
  std::vector<uint64_t> batch;
  const size_t batch_size = std::max<size_t>(4096, memory / 16 / sizeof(uint64_t));
  std::vector<uint64_t> scratch;
  auto add_batch = [&]() -> Status {
    radix_sort_by(batch, scratch, [](uint64_t id) { return id; });
    batch.erase(std::unique(batch.begin(), batch.end()), batch.end());
    for (uint64_t id : batch) WEAVER_RETURN_IF_ERROR(corners.add({id, 0}));
    batch.clear();
    return Status::Ok();
  };
  elements_ = 0;
  WEAVER_RETURN_IF_ERROR(scan_selected(mesh, sel, true, [&](MeshElement& e) {
    ++elements_;
    batch.insert(batch.end(), e.nodes.begin(), e.nodes.end());
    return batch.size() >= batch_size ? add_batch() : Status::Ok();
  }));
  WEAVER_RETURN_IF_ERROR(add_batch());
  std::vector<uint64_t>().swap(batch);
  std::vector<uint64_t>().swap(scratch);
  WEAVER_RETURN_IF_ERROR(corners.finish());
  ExternalSorter sorter(scratch_dir + "/sort", memory / 4);
  uint64_t last = UINT64_MAX;
  for (;;) {
    KeyTag kt;
    bool done = false;
    WEAVER_RETURN_IF_ERROR(corners.next(&kt, &done));
    if (done) break;
    if (kt.key == last) continue;
    last = kt.key;
    if (with_anchors) {
      WEAVER_RETURN_IF_ERROR(add_with_anchors(mesh, kt.key, sorter));
    } else {
      WEAVER_RETURN_IF_ERROR(sorter.add({kt.key, 0}));
    }
  }
  knows_dangling_ = with_anchors;
  dangling_ = 0;
  WEAVER_RETURN_IF_ERROR(sorter.finish());
  scratch_dir_ = scratch_dir;
  scratch_file_ = scratch_dir + "/local_nodes.bt";
  std::unique_ptr<File> file;
  WEAVER_RETURN_IF_ERROR(open_posix_file(scratch_file_, OpenMode::kCreateTruncate, &file));
  TableOptions t;
  t.key_kind = KeyKind::kNode;
  t.packed = true;
  // memory / 2 - 1 MiB for the tree's pool: the rest holds the ids found lately.
  found_.assign(size_t{1} << kFoundBits, Found{});
  const uint64_t found_bytes = found_.size() * sizeof(Found);
  WEAVER_RETURN_IF_ERROR(BTree::create(
      std::move(file), t, std::max<uint64_t>(memory / 2, 2 * found_bytes) - found_bytes, &tree_));
  nodes_ = 0;
  last = 0;
  for (;;) {
    KeyTag kt;
    bool done = false;
    WEAVER_RETURN_IF_ERROR(sorter.next(&kt, &done));
    if (done) break;
    if (nodes_ > 0 && kt.key == last) continue;
    dangling_ += kt.tag != uint64_t(NodeKind::kAnchored);
    WEAVER_RETURN_IF_ERROR(tree_->append(kt.key, nullptr));
    last = kt.key;
    ++nodes_;
  }
  return Status::Ok();
}

LocalNodes::~LocalNodes() {
  if (tree_ == nullptr) return;
  cursor_ = BTreeCursor();  // it pins a page of the tree: let go first
  tree_.reset();
  std::remove(scratch_file_.c_str());
  ::rmdir(scratch_dir_.c_str());
}

Status LocalNodes::local_id(uint64_t global, uint64_t* local) {
  if (identity_) return *local = global, Status::Ok();
  Found& f = found_[(global * 0x9E3779B97F4A7C15ULL) >> (64 - kFoundBits)];
  if (f.global == global) return *local = f.local, Status::Ok();
  bool present = false;
  WEAVER_RETURN_IF_ERROR(tree_->rank_exact(global, local, &present));
  if (!present) {
    return Status::Internal("node " + std::to_string(global) + " is not in the selection");
  }
  f = {global, *local};
  return Status::Ok();
}

Status LocalNodes::start() {
  at_ = 0;
  if (identity_) return Status::Ok();
  return tree_->seek_cursor(0, &cursor_);
}

bool LocalNodes::valid() const { return identity_ ? at_ < nodes_ : cursor_.valid(); }

uint64_t LocalNodes::global() const { return identity_ ? at_ : cursor_.key(); }

Status LocalNodes::next() {
  if (identity_) return ++at_, Status::Ok();
  return cursor_.next();
}

}  // namespace weaver
