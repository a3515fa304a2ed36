// A part of a mesh to export: the elements of an id range (a piece of a
// pvtu, a part of a partition) that meet a box, and the nodes they use,
// numbered compactly in global id order.  The node set is built out of core:
// the corner ids of the selected elements (and the anchors of dangling ones,
// so that every constraint can be written) go through an external sort into
// a scratch B+tree of global ids, where a node's local id is its rank.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "mesh/mesh_reader.h"
#include "mesh/part_map.h"
#include "storage/btree.h"

namespace weaver {

struct Selection {
  uint64_t first = 0, end = UINT64_MAX;  // element ids [first, end)
  bool has_box = false;
  Coord lo, hi;                    // the box in ticks, bounds included
  const PartMap* parts = nullptr;  // if set: only the elements of `part`
  uint32_t part = 0;               // the part selected (by parts, or by the id range)

  bool whole() const { return first == 0 && end == UINT64_MAX && !has_box && parts == nullptr; }
  // Whether element id (octant o) of the id range is selected: it shares a
  // point with the box and lies in the part.
  Status keeps(uint64_t id, const Octant& o, bool* keep) const {
    *keep = true;
    if (has_box) {
      const uint32_t s = octant_edge(o);
      *keep = o.x <= hi.x && o.x + s >= lo.x && o.y <= hi.y && o.y + s >= lo.y && o.z <= hi.z &&
              o.z + s >= lo.z;
    }
    if (!*keep || parts == nullptr) return Status::Ok();
    uint32_t p = 0;
    WEAVER_RETURN_IF_ERROR(parts->part_of(id, &p));
    *keep = p == part;
    return Status::Ok();
  }
};

// Calls fn for each selected element in id order, with its corners' global
// node ids when with_nodes (looked up a batch at a time).  With a box only
// the box's runs of ids are read (mesh/octant_query.h), not the mesh.
Status scan_selected(Mesh& mesh, const Selection& sel, bool with_nodes,
                     const std::function<Status(MeshElement&)>& fn);

// How many elements share a point with sel's box (sel.has_box), whatever
// its id range and part: counted by rank, without reading them.
Status count_box_elements(Mesh& mesh, const Selection& sel, uint64_t* count);

// The nodes of a selection, local id = rank in global id order.  For the
// whole mesh local ids are the global ones and nothing is built.
class LocalNodes {
 public:
  LocalNodes() = default;
  ~LocalNodes();  // removes the scratch files
  LocalNodes(const LocalNodes&) = delete;
  LocalNodes& operator=(const LocalNodes&) = delete;

  // with_anchors: also the anchors of every dangling node the elements use.
  // Counts the selected elements too.  Scratch files go to scratch_dir.
  Status build(Mesh& mesh, const Selection& sel, bool with_anchors, const std::string& scratch_dir,
               uint64_t memory);
  uint64_t node_count() const { return nodes_; }
  uint64_t element_count() const { return elements_; }
  // Whether build counted the dangling nodes of the set (it did with
  // anchors, or for the whole mesh: false), and how many.
  bool knows_dangling() const { return !identity_ && knows_dangling_; }
  uint64_t dangling_count() const { return dangling_; }
  // The local id of a node of the selection: a search of the node set, or
  // a look at the ids found lately (an element's corners are corners of
  // its neighbours too, which come soon after it in Z-order).
  Status local_id(uint64_t global, uint64_t* local);
  // Global ids in order: start, then valid / global / next.
  Status start();
  bool valid() const;
  uint64_t global() const;
  Status next();

 private:
  bool identity_ = true, knows_dangling_ = false;
  uint64_t nodes_ = 0, elements_ = 0, at_ = 0, dangling_ = 0;
  std::unique_ptr<BTree> tree_;
  BTreeCursor cursor_;
  std::string scratch_dir_, scratch_file_;
  // Global id -> local id of nodes asked lately, a slot per hash of the
  // global id (empty: global UINT64_MAX).  Counted in the selection's share.
  struct Found {
    uint64_t global = UINT64_MAX, local = 0;
  };
  static constexpr int kFoundBits = 16;  // 1 MiB
  std::vector<Found> found_;
};

}  // namespace weaver
