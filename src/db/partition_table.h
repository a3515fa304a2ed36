// The partition table: which part each element belongs to, as runs.  One
// record per run of consecutive element ids in one part: key = the first
// element id of the run, payload = the part.  A space-filling-curve partition
// of N parts is N records; a graph partition one record per change of part
// along the ids.  The part of element i is the payload of the floor of i.
// Metadata: "method=sfc|graph;parts=N;weight=none|level".  Derived from the
// octant table (element ids are its ranks): replacing the octants drops it.
#pragma once

namespace weaver {

inline constexpr char kPartitionTable[] = "partition";
inline constexpr char kPartitionSchema[] = "part:u32";

}  // namespace weaver
