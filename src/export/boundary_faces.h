// The boundary table (db/boundary_table.h) as the exports write it: the
// records of the selected elements, with their local element ids, and a
// record's quadrilateral.  Internal to src/export.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "export/writers.h"

namespace weaver {

struct BoundaryRecord {
  uint64_t element = 0;  // local id: the element's place among the selected
  uint64_t global = 0;   // its id in the whole mesh
  Octant octant;
  int face = 0, part = 0;
  uint8_t kind = 0;                           // BoundaryKind
  const MeshElement* mesh_element = nullptr;  // the element, with its material
};

// The records of the job's selected elements, in local element order.
Status for_each_boundary(ExportJob& job, const std::function<Status(const BoundaryRecord&)>& fn);
// How many there are (the table's size for the whole mesh).
Status count_boundary(ExportJob& job, uint64_t* n);
// The corners of the record's face or quarter (ticks), counter-clockwise
// seen from outside the element.
std::array<Coord, 4> boundary_quad(const Octant& o, int face, int part);
// NAME_boundary.vtu beside NAME.vtu (or beside NAME).
std::string boundary_vtu_path(const std::string& out);
// The boundary of the job's selection as a vtu of quadrilaterals, each with
// its element id, face, part and kind; points of their own (four a quad).
Status write_boundary_vtu(ExportJob& job, const std::string& path);

// msh's boundary (export_msh.cc): the quads of the free surface and of the
// absorbing sides as two surface entities in physical groups "free_surface"
// (1) and "absorbing" (2), beside the volume's group "volume" (3) so that
// Gmsh keeps every element when it saves; a quarter face's corners that are
// no node of the selection (an edge's midpoint beside open quarters) are
// extra nodes, numbered after the mesh's.
class MshBoundary {
 public:
  // Counts the quads and finds the extra nodes (held sorted in memory: a
  // few per quarter face).  Nothing when the mesh has no boundary table.
  Status plan(ExportJob& job);
  bool present() const { return present_; }
  uint64_t quads(int kind) const { return counts_[kind]; }
  uint64_t extra_nodes() const { return extra_.size(); }
  // $PhysicalNames and $Entities.
  std::string head() const;
  // The extra nodes' block of $Nodes (tags first_tag on).
  Status write_extra_nodes(ExportJob& job, Section& out, uint64_t first_tag) const;
  // The quads of one kind (1 free surface, 0 absorbing), tags *tag + 1 on.
  Status write_quads(ExportJob& job, Section& out, int kind, uint64_t* tag);
  // The element of each quad of one kind, in write_quads' order.
  Status for_each_quad(ExportJob& job, int kind,
                       const std::function<Status(const MeshElement&)>& fn);

 private:
  // The 1-based tag of the point c: a node of the selection, or an extra one.
  Status tag_of(ExportJob& job, Coord c, uint64_t* tag, bool* extra) const;
  bool present_ = false;
  uint64_t counts_[2] = {0, 0};
  std::vector<uint64_t> extra_;  // node keys, sorted
  uint64_t nodes_ = 0;
};

}  // namespace weaver
