// The node table: one record per mesh node, keyed by node key (the Morton
// code of its coordinate), in id order.  The payload is the node kind only:
// ids are ranks and anchors follow from coordinate and kind (schema/node.h).
#pragma once

namespace weaver {

inline constexpr char kNodeTable[] = "nodes";
inline constexpr char kNodeSchema[] = "kind:u8";  // NodeKind

}  // namespace weaver
