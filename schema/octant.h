// Octants of the weaver address space and their arithmetic.
//
// The root octant spans 2^20 ticks per axis; an octant of level l (0..20) has
// edge 2^(20-l) ticks and a lower corner that is a multiple of its edge.
//
// Validity classes (every function says which it accepts):
//   octant   level <= kMaxLevel, corner < 2^20 per axis, corner aligned to
//            the edge.  Checked by octant_is_valid().
//   pixel    a tick point strictly inside the root: each axis < 2^20.
//            Checked by pixel_is_valid().
//   node     a tick point up to and including the far side: each axis
//            <= 2^20 (21 bits).  Checked by node_is_valid().
// Functions assert their REQUIRES clauses in debug builds.
#pragma once

#include <array>
#include <bit>
#include <cassert>
#include <cstdint>
#include <string>

#include "schema/morton.h"

namespace weaver {

// The deepest level. 20 levels keep an octant corner within 60 bits of Morton
// code, which lets an octant key pack into one 64-bit word (see octant_key).
// Fixed by DESIGN.md: do not change, keys on disk depend on it.
inline constexpr int kMaxLevel = 20;
inline constexpr uint32_t kRootEdge = 1u << kMaxLevel;

struct Octant {
  uint32_t x = 0, y = 0, z = 0;
  uint8_t level = 0;
  friend bool operator==(const Octant&, const Octant&) = default;
};

// Edge length in ticks of an octant at `level`.  REQUIRES: 0 <= level <= 20.
constexpr uint32_t octant_edge(int level) {
  assert(level >= 0 && level <= kMaxLevel);
  return kRootEdge >> level;
}
constexpr uint32_t octant_edge(const Octant& o) { return octant_edge(o.level); }

constexpr bool pixel_is_valid(Coord p) {
  return p.x < kRootEdge && p.y < kRootEdge && p.z < kRootEdge;
}
constexpr bool node_is_valid(Coord p) {
  return p.x <= kRootEdge && p.y <= kRootEdge && p.z <= kRootEdge;
}
constexpr bool octant_is_valid(const Octant& o) {
  if (o.level > kMaxLevel) return false;
  const uint32_t mask = (kRootEdge >> o.level) - 1;
  return pixel_is_valid({o.x, o.y, o.z}) && ((o.x | o.y | o.z) & mask) == 0;
}

constexpr Octant octant_root() { return {0, 0, 0, 0}; }
constexpr Coord octant_corner(const Octant& o) { return {o.x, o.y, o.z}; }

// Corner k (0..7) of the octant: x varies fastest.  Accepts: octant.
// Returns: node.
constexpr Coord octant_corner(const Octant& o, int k) {
  assert(octant_is_valid(o) && k >= 0 && k < 8);
  const uint32_t s = octant_edge(o);
  return {o.x + s * (k & 1), o.y + s * ((k >> 1) & 1), o.z + s * ((k >> 2) & 1)};
}

// The ancestor of `o` at `level`.  REQUIRES: octant, level <= o.level.
constexpr Octant octant_ancestor(const Octant& o, int level) {
  assert(octant_is_valid(o) && level >= 0 && level <= o.level);
  const uint32_t mask = ~(octant_edge(level) - 1);
  return {o.x & mask, o.y & mask, o.z & mask, static_cast<uint8_t>(level)};
}

// REQUIRES: octant, level > 0.
constexpr Octant octant_parent(const Octant& o) {
  assert(octant_is_valid(o) && o.level > 0);
  return octant_ancestor(o, o.level - 1);
}

// Child k (0..7), x fastest.  REQUIRES: octant, level < kMaxLevel.
constexpr Octant octant_child(const Octant& o, int k) {
  assert(octant_is_valid(o) && o.level < kMaxLevel && k >= 0 && k < 8);
  const uint32_t h = octant_edge(o.level + 1);
  return {o.x + h * (k & 1), o.y + h * ((k >> 1) & 1), o.z + h * ((k >> 2) & 1),
          static_cast<uint8_t>(o.level + 1)};
}

// Which child of its parent `o` is (0..7).  REQUIRES: octant, level > 0.
constexpr int octant_child_id(const Octant& o) {
  assert(octant_is_valid(o) && o.level > 0);
  const int shift = kMaxLevel - o.level;
  return static_cast<int>(((o.x >> shift) & 1) | (((o.y >> shift) & 1) << 1) |
                          (((o.z >> shift) & 1) << 2));
}

// Whether tick point p lies in the half-open box [corner, corner + edge).
// Accepts: octant, and any point (a point past the root is simply outside).
constexpr bool octant_contains_point(const Octant& o, Coord p) {
  assert(octant_is_valid(o));
  const uint32_t s = octant_edge(o);
  // Unsigned subtraction wraps for p < corner, so one compare per axis suffices.
  return p.x - o.x < s && p.y - o.y < s && p.z - o.z < s;
}

// Whether the octant meets the closed tick box [lo, hi] (bounds included),
// and whether it lies wholly inside it.  Accepts: octant.
constexpr bool octant_meets_box(const Octant& o, Coord lo, Coord hi) {
  const uint32_t last = octant_edge(o) - 1;
  return o.x <= hi.x && o.x + last >= lo.x && o.y <= hi.y && o.y + last >= lo.y && o.z <= hi.z &&
         o.z + last >= lo.z;
}
constexpr bool octant_in_box(const Octant& o, Coord lo, Coord hi) {
  const uint32_t last = octant_edge(o) - 1;
  return o.x >= lo.x && o.x + last <= hi.x && o.y >= lo.y && o.y + last <= hi.y && o.z >= lo.z &&
         o.z + last <= hi.z;
}

// Whether `a` is a strict ancestor of `b`.  Accepts: octants.
constexpr bool octant_is_ancestor(const Octant& a, const Octant& b) {
  assert(octant_is_valid(a) && octant_is_valid(b));
  if (a.level >= b.level) return false;
  const int shift = kMaxLevel - a.level;  // up to 20: fine for uint32_t
  return (a.x >> shift) == (b.x >> shift) && (a.y >> shift) == (b.y >> shift) &&
         (a.z >> shift) == (b.z >> shift);
}

// The smallest octant containing both.  Accepts: octants.
constexpr Octant octant_nearest_common_ancestor(const Octant& a, const Octant& b) {
  assert(octant_is_valid(a) && octant_is_valid(b));
  const uint32_t diff = (a.x ^ b.x) | (a.y ^ b.y) | (a.z ^ b.z);
  int level = kMaxLevel - static_cast<int>(std::bit_width(diff));
  if (a.level < level) level = a.level;
  if (b.level < level) level = b.level;
  return octant_ancestor(a, level);
}

// A neighbour direction: each component in {-1, 0, 1}, not all zero.  One
// non-zero component crosses a face, two an edge, three a corner.
struct Direction {
  int8_t dx = 0, dy = 0, dz = 0;
  enum class Kind { kFace = 1, kEdge = 2, kCorner = 3 };

  constexpr int nonzero() const { return (dx != 0) + (dy != 0) + (dz != 0); }
  constexpr Kind kind() const { return static_cast<Kind>(nonzero()); }
  constexpr bool is_valid() const {
    return dx >= -1 && dx <= 1 && dy >= -1 && dy <= 1 && dz >= -1 && dz <= 1 && nonzero() > 0;
  }
  friend bool operator==(const Direction&, const Direction&) = default;
};

namespace octant_detail {
// The directions whose kind is in `kinds` (a bit per Kind), z slowest, x fastest.
template <size_t N>
constexpr std::array<Direction, N> directions(unsigned kinds) {
  std::array<Direction, N> out{};
  size_t n = 0;
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const Direction d{static_cast<int8_t>(dx), static_cast<int8_t>(dy),
                          static_cast<int8_t>(dz)};
        if (d.nonzero() > 0 && (kinds >> d.nonzero() & 1)) out[n++] = d;
      }
  return out;
}
}  // namespace octant_detail

inline constexpr auto kFaceDirections = octant_detail::directions<6>(1u << 1);
inline constexpr auto kEdgeDirections = octant_detail::directions<12>(1u << 2);
inline constexpr auto kCornerDirections = octant_detail::directions<8>(1u << 3);
// What 2:1 balance looks at (weaver balances across faces and edges).
inline constexpr auto kFaceAndEdgeDirections = octant_detail::directions<18>((1u << 1) | (1u << 2));
inline constexpr auto kAllDirections =
    octant_detail::directions<26>((1u << 1) | (1u << 2) | (1u << 3));

// The same-size neighbour of `o` in direction d.  Returns false when it lies
// outside the root.  REQUIRES: octant, d.is_valid().
constexpr bool octant_neighbour(const Octant& o, Direction d, Octant* out) {
  assert(octant_is_valid(o) && d.is_valid());
  const int64_t s = octant_edge(o);
  const int64_t nx = o.x + d.dx * s, ny = o.y + d.dy * s, nz = o.z + d.dz * s;
  const int64_t lim = kRootEdge;
  if (nx < 0 || ny < 0 || nz < 0 || nx >= lim || ny >= lim || nz >= lim) return false;
  *out = {static_cast<uint32_t>(nx), static_cast<uint32_t>(ny), static_cast<uint32_t>(nz), o.level};
  return true;
}

// ---------------------------------------------------------------------------
// Keys.
//
// The logical octant key is (Morton code of the lower corner, level), ordered
// by Morton then level, so an ancestor sorts just before its descendants and
// the leaves of an octree sort in preorder (Z-order).  On disk and in memory
// it is packed into one 64-bit word with the same order:
//
//   key = (m >> 3) << 7  |  (level < 20 ? level : 20 + (m & 7))
//
// m < 2^60 and, below level 20, m's low 3 bits are zero, so each group of 8
// Morton codes [8j, 8j+8) owns the 128 keys [128j, 128j+128): levels 0..19 at
// 8j take slots 0..19 and the 8 level-20 octants take slots 20..27, in
// (Morton, level) order.  Do not change: on disk.
// ---------------------------------------------------------------------------

inline constexpr uint64_t kKeyLevel20Slot = 20;

constexpr uint64_t octant_morton(const Octant& o) { return morton_encode(o.x, o.y, o.z); }

// Accepts: octant.
constexpr uint64_t octant_key(const Octant& o) {
  assert(octant_is_valid(o));
  const uint64_t m = octant_morton(o);
  const uint64_t slot = o.level < kMaxLevel ? o.level : kKeyLevel20Slot + (m & 7);
  return ((m >> 3) << 7) | slot;
}

// Whether `key` is the packed key of some valid octant.
constexpr bool octant_key_is_valid(uint64_t key) {
  const uint64_t slot = key & 127;
  if (slot >= kKeyLevel20Slot + 8) return false;
  if (slot >= kKeyLevel20Slot) return true;
  const uint64_t m = (key >> 7) << 3;
  const int zeros = 3 * (kMaxLevel - static_cast<int>(slot));  // low Morton bits that must be 0
  return zeros >= 64 ? m == 0 : (m & ((uint64_t{1} << zeros) - 1)) == 0;
}

// REQUIRES: octant_key_is_valid(key).
constexpr Octant octant_from_key(uint64_t key) {
  assert(octant_key_is_valid(key));
  const uint64_t slot = key & 127;
  uint64_t m = (key >> 7) << 3;
  uint8_t level = static_cast<uint8_t>(slot);
  if (slot >= kKeyLevel20Slot) {
    m |= slot - kKeyLevel20Slot;
    level = kMaxLevel;
  }
  const Coord c = morton_decode(m);
  return {c.x, c.y, c.z, level};
}

// The key of the same-size neighbour in direction d of the octant with key
// `key`, without decoding (octant_neighbour's answer, for the hot loops of
// balance); false when it lies outside the root.
// REQUIRES: octant_key_is_valid(key), its level below kMaxLevel, d.is_valid().
constexpr bool octant_key_neighbour(uint64_t key, Direction d, uint64_t* out) {
  assert(octant_key_is_valid(key) && (key & 127) < kMaxLevel && d.is_valid());
  const int level = static_cast<int>(key & 127), bit = kMaxLevel - level;
  uint64_t m = (key >> 7) << 3;
  const int delta[3] = {d.dx, d.dy, d.dz};
  for (int axis = 0; axis < 3; ++axis) {
    const uint64_t axis_bits = 0x1249249249249249ULL << axis;
    if (delta[axis] < 0) {
      if ((m & axis_bits) == 0) return false;  // at the root's near side
      m = morton_step_back(m, axis, bit);
    } else if (delta[axis] > 0) {
      m = morton_step(m, axis, bit);
      if (m >> (3 * kMaxLevel + axis) & 1) return false;  // past the far side
    }
  }
  *out = ((m >> 3) << 7) | static_cast<uint64_t>(level);
  return true;
}

// octant_key_neighbour's answers for one key in many directions: each axis
// stepped back and forward once, a neighbour's code then the parts of
// its three axes put together (for the ripple, which asks for up to 18
// neighbours of a key).  The same keys, and false (and 0, the root's key:
// no neighbour's) where octant_key_neighbour says false.
// REQUIRES: as octant_key_neighbour's.
class KeyNeighbours {
 public:
  constexpr explicit KeyNeighbours(uint64_t key) : level_(key & 127) {
    assert(octant_key_is_valid(key) && (key & 127) < kMaxLevel);
    const int bit = kMaxLevel - static_cast<int>(level_);
    const uint64_t m = (key >> 7) << 3;
    for (int axis = 0; axis < 3; ++axis) {
      const uint64_t axis_bits = 0x1249249249249249ULL << axis;
      part_[axis][1] = m & axis_bits, inside_[axis][1] = true;
      inside_[axis][0] = (m & axis_bits) != 0;  // not at the root's near side
      part_[axis][0] = inside_[axis][0] ? morton_step_back(m, axis, bit) & axis_bits : 0;
      const uint64_t ahead = morton_step(m, axis, bit);
      inside_[axis][2] = !(ahead >> (3 * kMaxLevel + axis) & 1);  // not past the far side
      part_[axis][2] = ahead & axis_bits;
    }
  }
  constexpr bool neighbour(Direction d, uint64_t* out) const {
    assert(d.is_valid());
    const int i[3] = {d.dx + 1, d.dy + 1, d.dz + 1};
    const uint64_t m = part_[0][i[0]] | part_[1][i[1]] | part_[2][i[2]];
    const bool inside = inside_[0][i[0]] & inside_[1][i[1]] & inside_[2][i[2]];
    *out = inside ? ((m >> 3) << 7) | level_ : 0;
    return inside;
  }

 private:
  uint64_t level_;
  uint64_t part_[3][3] = {};  // by axis and step (-1, 0, +1): the axis's bits of the code
  bool inside_[3][3] = {};
};

// The Morton code of the octant's corner, straight from its key (no decode).
// REQUIRES: octant_key_is_valid(key).
constexpr uint64_t octant_key_morton(uint64_t key) {
  assert(octant_key_is_valid(key));
  const uint64_t slot = key & 127;
  return ((key >> 7) << 3) | (slot >= kKeyLevel20Slot ? slot - kKeyLevel20Slot : 0);
}
// octant_key_morton's arithmetic for any 64-bit value: for a search by
// Morton code among keys not yet checked.
constexpr uint64_t octant_key_morton_of_any(uint64_t key) {
  const uint64_t slot = key & 127;
  return ((key >> 7) << 3) | (slot >= kKeyLevel20Slot ? (slot - kKeyLevel20Slot) & 7 : 0);
}
// REQUIRES: octant_key_is_valid(key).
constexpr int octant_key_level(uint64_t key) {
  assert(octant_key_is_valid(key));
  const uint64_t slot = key & 127;
  return slot >= kKeyLevel20Slot ? kMaxLevel : static_cast<int>(slot);
}

// The key of the octant's ancestor at `level`, without decoding
// (octant_ancestor's answer, for scans of every leaf).
// REQUIRES: octant_key_is_valid(key), 0 <= level < its level.
constexpr uint64_t octant_key_ancestor(uint64_t key, int level) {
  const uint64_t m = octant_key_morton(key) & ~((uint64_t{1} << (3 * (kMaxLevel - level))) - 1);
  return ((m >> 3) << 7) | static_cast<uint64_t>(level);
}

// The key of the octant's parent, without decoding (octant_parent's answer,
// for balance's scan of every leaf).
// REQUIRES: octant_key_is_valid(key), its level above 0.
constexpr uint64_t octant_key_parent(uint64_t key) {
  return octant_key_ancestor(key, octant_key_level(key) - 1);
}

// octant_from_key's answer written into *o one field at a time.  For an
// octant kept in memory and read again soon (a cache of recent leaves):
// assigning the returned struct copies its 13 bytes as two overlapping
// 8-byte moves, and a later load that spans both does not forward from
// them (a stall of some 15 cycles).
// REQUIRES: octant_key_is_valid(key).
constexpr void octant_decode_into(uint64_t key, Octant* o) {
  const Coord c = morton_decode(octant_key_morton(key));
  o->x = c.x;
  o->y = c.y;
  o->z = c.z;
  o->level = static_cast<uint8_t>(octant_key_level(key));
}

// Which child of its parent the octant with this key is (0..7, x fastest:
// octant_child_id's answer, without decoding).
// REQUIRES: octant_key_is_valid(key), its level above 0.
constexpr int octant_key_child_id(uint64_t key) {
  const int level = octant_key_level(key);
  return static_cast<int>(octant_key_morton(key) >> (3 * (kMaxLevel - level)) & 7);
}

// The key of child c (0..7, x fastest) of the octant with this key, without
// decoding.  REQUIRES: octant_key_is_valid(key), its level below kMaxLevel.
constexpr uint64_t octant_key_child(uint64_t key, int c) {
  const int level = octant_key_level(key) + 1;
  const uint64_t m = octant_key_morton(key) | (uint64_t(c) << (3 * (kMaxLevel - level)));
  const uint64_t slot = level < kMaxLevel ? uint64_t(level) : kKeyLevel20Slot + (m & 7);
  return ((m >> 3) << 7) | slot;
}

// What the keys of two octants of `level` next to each other in Z-order
// differ by (the later's minus the earlier's): the octants of one level
// inside an octant have keys key_0 + i * stride, i their Z-order there.
// REQUIRES: level < kMaxLevel (the level-20 keys hold a code's last bits
// in their level byte).
constexpr uint64_t octant_key_stride(int level) {
  assert(level >= 0 && level < kMaxLevel);
  return uint64_t{1} << (3 * (kMaxLevel - level) - 3 + 7);
}

// The key of the level-20 octant whose Morton code is m (a pixel's code).
// REQUIRES: m < 2^60.
constexpr uint64_t pixel_key_of_morton(uint64_t m) {
  assert(m < (uint64_t{1} << (3 * kMaxLevel)));
  return ((m >> 3) << 7) | (kKeyLevel20Slot + (m & 7));
}

// The key of the level-20 octant at pixel p; the floor of this key in a leaf
// table is the leaf that contains p, if any (the "aggregate hit").
// Accepts: pixel.
constexpr uint64_t pixel_key(Coord p) {
  assert(pixel_is_valid(p));
  return pixel_key_of_morton(octant_morton({p.x, p.y, p.z, kMaxLevel}));
}

// octant_key_subtree_end's arithmetic for any 64-bit value, a valid key or
// not: packed leaf pages (storage/packed_leaf.h) predict each octant key from
// the one before with it, whatever the keys hold.  Do not change: on disk.
constexpr uint64_t octant_key_subtree_end_of_any(uint64_t key) {
  const uint64_t slot = key & 127;
  if (slot >= kKeyLevel20Slot) return key + 1;  // level 20: the next slot
  const int level = static_cast<int>(slot);
  const uint64_t span = uint64_t{1} << (3 * (kMaxLevel - level));
  const uint64_t m_end = ((key >> 7) << 3) + span;  // a multiple of 8 below level 20
  if (m_end >> (3 * kMaxLevel)) return UINT64_MAX;  // the subtree reaches the root's end
  return (m_end >> 3) << 7;
}

// The smallest key greater than every key in the subtree of the octant with
// this key; UINT64_MAX (never a valid key) for the root.
// REQUIRES: octant_key_is_valid(key).
constexpr uint64_t octant_key_subtree_end(uint64_t key) {
  assert(octant_key_is_valid(key));
  return octant_key_subtree_end_of_any(key);
}
// The same for an octant.  Accepts: octant.
constexpr uint64_t octant_key_subtree_end(const Octant& o) {
  return octant_key_subtree_end(octant_key(o));
}

// The node key of a node coordinate: its Morton code.  Accepts: node.
constexpr uint64_t node_key(Coord p) {
  assert(node_is_valid(p));
  return morton_encode(p);
}

// node_is_valid(morton_decode(key)) without decoding: no coordinate past
// 2^20.  Its bit 20 is key bit 60 + axis; with it set, the axis's lower
// bits must be clear.  Key bit 63 (x's bit 21, which morton_decode drops)
// must be clear too: no node's key has it.  For scans of every node
// (weaver verify).
constexpr bool node_key_is_valid(uint64_t key) {
  bool valid = (key >> 63) == 0;
  for (int a = 0; a < 3; ++a) {
    const uint64_t below = (0x1249249249249249ULL << a) & ((uint64_t{1} << 60) - 1);
    valid &= !(((key >> (60 + a)) & 1) && (key & below) != 0);
  }
  return valid;
}

// "(x y z level)" in ticks, for messages.
inline std::string describe_octant(const Octant& o) {
  return "(" + std::to_string(o.x) + " " + std::to_string(o.y) + " " + std::to_string(o.z) + " " +
         std::to_string(o.level) + ")";
}

}  // namespace weaver
