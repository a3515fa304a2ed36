// Reading the octant text format (DESIGN.md): one leaf per line, "x y z level"
// in ticks; blank lines and lines starting with '#' are ignored.
#pragma once

#include <cstdint>
#include <cstdio>
#include <functional>
#include <string>
#include <vector>

#include "schema/octant.h"
#include "schema/status.h"

namespace weaver {

// Calls on_octant(octant, line_number) for every octant line of `path`, in
// file order.  A malformed line, a coordinate or level out of range, or a
// misaligned corner stops the read with InvalidArgument "PATH:LINE: reason".
// If on_octant returns an error, reading stops and that error is returned.
Status read_octant_text(const std::string& path,
                        const std::function<Status(const Octant&, uint64_t)>& on_octant);

// Writes octants in the text format, one per line, in the given order.
Status write_octant_text(const std::string& path, const std::vector<Octant>& octants,
                         const std::string& header_comment);

}  // namespace weaver
