// The boundary table (db/boundary_table.h) as the exports write it: the
// records of the selected elements, with their local element ids, and a
// record's quadrilateral.  Internal to src/export.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <string>

#include "export/writers.h"

namespace weaver {

struct BoundaryRecord {
  uint64_t element = 0;  // local id: the element's place among the selected
  uint64_t global = 0;   // its id in the whole mesh
  Octant octant;
  int face = 0, part = 0;
  uint8_t kind = 0;  // BoundaryKind
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

}  // namespace weaver
