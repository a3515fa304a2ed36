// The product's checksum policy, alone in its object file so that a program
// can link its own definition instead (the fuzz targets do: fuzz/checksums_off.cc).
#include "storage/checksum.h"

namespace weaver {

bool checksums_enforced() { return true; }

}  // namespace weaver
