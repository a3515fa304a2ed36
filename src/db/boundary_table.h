// The boundary table: every element face, or quarter of a face, with no
// element across it, and what lies there.  One record a face or quarter:
// key = element id << 6 | face << 3 | part (face 0-5 as x-, x+, y-, y+,
// z- (up), z+ (down); part 0 the whole face, 1-4 the quarter (u, v) =
// ((part-1) & 1, (part-1) >> 1), u and v the face's two in-plane axes in x,
// y, z order), so the records of an element are in face, then part, order
// and the elements in id order; payload = its kind.  Derived from the
// octant table (element ids are its ranks): replacing the octants drops it.
// Metadata: the counts, "faces=N;free_surface=N;sides=N".
#pragma once

#include <cstdint>

namespace weaver {

inline constexpr char kBoundaryTable[] = "boundary";
inline constexpr char kBoundarySchema[] = "kind:u8";

// What lies across a boundary face.
enum class BoundaryKind : uint8_t {
  kDomainSide = 0,   // the domain's x-, x+, y-, y+ or bottom side: absorbing
  kFreeSurface = 1,  // the air (the domain's top included): traction free
};

inline uint64_t boundary_key(uint64_t element, int face, int part) {
  return element << 6 | uint64_t(face) << 3 | uint64_t(part);
}
inline uint64_t boundary_element(uint64_t key) { return key >> 6; }
inline int boundary_face(uint64_t key) { return int(key >> 3) & 7; }
inline int boundary_part(uint64_t key) { return int(key) & 7; }

}  // namespace weaver
