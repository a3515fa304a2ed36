// The name of the aggregate table (its layout and builder are in
// query/aggregates.h).  Derived from the octant table: replacing the
// octants drops it.
#pragma once

namespace weaver {

inline constexpr char kAggregateTable[] = "aggregates";

}  // namespace weaver
