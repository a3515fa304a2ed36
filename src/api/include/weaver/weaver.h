// weaver's library API: open a mesh database read-only and ask it what the
// command line's `weaver query` and `weaver shell` answer, from a program.
//
//   #include <weaver/weaver.h>
//   using namespace weaver::api;
//   std::string error;
//   auto db = MeshDatabase::open("basin.db", &error);
//   if (!db) { std::cerr << error << "\n"; return 1; }
//   PointHit hit;
//   if (db->locate({440000, 576000, 1000}, &hit) && hit.inside) ...
//   ElementCursor e = db->elements();
//   for (Element el; e.next(&el);) ...
//   if (!e.ok()) std::cerr << db->last_error() << "\n";
//
// Coordinates are ticks (integers; see units() for metres).  Element ids are
// the leaves' ranks in Z-order, node ids the nodes' ranks: the ids of every
// export.  One MeshDatabase per thread: it is not safe to share one.
// The surface is small on purpose and stays stable; weaver_c.h is the same
// for C, Fortran and Python (ctypes).
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace weaver {
class Explorer;
class SharedBatch;
class ElementScan;
class NodeScan;
}  // namespace weaver

namespace weaver::api {

struct Point {
  uint32_t x = 0, y = 0, z = 0;  // ticks
};

// The element holding a point.
struct PointHit {
  bool inside = false;  // false: outside the domain
  uint64_t element = 0;
  Point corner;  // the element's lowest corner
  int level = 0;
  uint32_t edge = 0;              // ticks
  float vp = 0, vs = 0, rho = 0;  // zeros without material
};

struct Element {
  uint64_t id = 0;
  Point corner;
  int level = 0;
  uint32_t edge = 0;
  std::array<uint64_t, 8> nodes{};  // corners 0..7, x fastest (0 without a mesh)
  float vp = 0, vs = 0, rho = 0;
};

enum class NodeKind { kAnchored = 0, kEdge = 1, kFace = 2 };

struct Node {
  uint64_t id = 0;
  Point at;
  NodeKind kind = NodeKind::kAnchored;
  int anchor_count = 0;               // 2 (edge) or 4 (face) when dangling
  std::array<uint64_t, 4> anchors{};  // the nodes it depends on
};

// An element across a face, edge or corner of another.
struct Neighbor {
  int dx = 0, dy = 0, dz = 0;  // the direction crossed: one non-zero for a face
  uint64_t element = 0;
};

struct Units {
  double tick_m = 1;                        // metres per tick
  std::array<double, 3> origin_m{0, 0, 0};  // where tick 0 lies
};

// Forward iteration over the elements in id order (with material and node
// ids); stop when next() is false, then check ok().
class ElementCursor {
 public:
  ElementCursor(ElementCursor&&) noexcept;
  ~ElementCursor();
  bool next(Element* out);
  bool ok() const;

 private:
  friend class MeshDatabase;
  ElementCursor(std::unique_ptr<weaver::ElementScan> scan, std::string* error);
  std::unique_ptr<weaver::ElementScan> scan_;
  std::string* error_;
  bool started_ = false, ok_ = true;
};

// The same over the nodes, with kinds and anchors.
class NodeCursor {
 public:
  NodeCursor(NodeCursor&&) noexcept;
  ~NodeCursor();
  bool next(Node* out);
  bool ok() const;

 private:
  friend class MeshDatabase;
  NodeCursor(std::unique_ptr<weaver::NodeScan> scan, std::string* error);
  std::unique_ptr<weaver::NodeScan> scan_;
  std::string* error_;
  bool started_ = false, ok_ = true;
};

class MeshDatabase {
 public:
  // Opens the database directory read-only within memory_bytes of caches;
  // null (and *error set) if it cannot.  The snapshot is the last commit.
  static std::unique_ptr<MeshDatabase> open(const std::string& path, std::string* error,
                                            uint64_t memory_bytes = uint64_t{256} << 20);
  ~MeshDatabase();

  uint64_t element_count() const;
  uint64_t node_count() const;  // 0 before `weaver extract`
  bool has_mesh() const;        // whether nodes exist
  bool has_material() const;
  Units units() const;

  // The same, answering a large batch of points (16384 or more) on
  // `threads` threads, as `weaver query --points --threads N` does: 1 (what
  // the call above does) answers on the calling thread alone, 0 takes one a
  // core.  memory_bytes is shared among them.  A program with threads of its
  // own, a MeshDatabase each, keeps 1.
  static std::unique_ptr<MeshDatabase> open(const std::string& path, std::string* error,
                                            uint64_t memory_bytes, int threads);
  int threads() const;  // what open() was given (0 made the cores' count)

  // Every call returns false on an error (see last_error()); an id past the
  // last one is an error, a point outside the domain is not.
  bool locate(Point p, PointHit* out);
  // n points in any order, answered in one sorted walk; out[i] answers p[i].
  bool locate(const Point* p, size_t n, PointHit* out);
  bool element(uint64_t id, Element* out);
  bool node(uint64_t id, Node* out);
  // The node at p: *found false if there is none.
  bool node_at(Point p, bool* found, uint64_t* id);
  // faces, edges, corners: which neighbours to list.
  bool neighbors(uint64_t element, bool faces, bool edges, bool corners,
                 std::vector<Neighbor>* out);
  // The elements whose closed boxes hold node id, in id order.
  bool node_elements(uint64_t node, std::vector<uint64_t>* out);
  // The dangling nodes that depend on node id.
  bool depends(uint64_t node, std::vector<uint64_t>* out);

  ElementCursor elements(uint64_t first = 0);
  NodeCursor nodes();  // REQUIRES: has_mesh()

  const std::string& last_error() const { return error_; }

 private:
  MeshDatabase() = default;
  bool open_explorers(const std::string& path, uint64_t memory_bytes, int threads,
                      std::string* error);

  std::unique_ptr<weaver::Explorer> ex_;
  std::string error_;
  std::vector<std::unique_ptr<weaver::Explorer>> helpers_;  // set_threads' others
  std::unique_ptr<weaver::SharedBatch> batch_;              // ex_ and the helpers
};

}  // namespace weaver::api
