// Linked into every fuzz target: readers skip the stored checksums, so that
// mutated pages, headers and manifests reach the decoders behind them.  This
// definition takes the place of storage/checksum_policy.cc's: the linker
// resolves checksums_enforced() here and never pulls that object from the
// storage library.
#include "storage/checksum.h"

namespace weaver {

bool checksums_enforced() { return false; }

}  // namespace weaver
