// The one collective the parallel stages need (weaver-mpi's ranks, or
// threads in the tests): an all-to-all of byte strings.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "schema/status.h"

namespace weaver {

// All to all, collective: blobs[s] goes to rank s; returns what each rank
// sent to this one, in rank order.  Every rank calls it the same number of
// times, also after an error (with nothing to send).
using RankExchange = std::function<Status(const std::vector<std::string>& blobs,
                                          std::vector<std::string>* received)>;

}  // namespace weaver
