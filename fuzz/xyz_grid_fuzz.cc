// The xyz grid file (model/xyz_grid.h): both passes over the same bytes.
#include "fuzz_util.h"
#include "model/xyz_grid.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  weaver::fuzz::MemoryPath file(data, size);
  weaver::XyzGrid grid;
  if (!weaver::scan_xyz_grid(file.path(), &grid).ok()) return 0;
  // Every point of an accepted file lands on the grid, inside it.
  const uint64_t n = uint64_t(grid.spec.nx) * grid.spec.ny * grid.spec.nz;
  if (n != grid.points) __builtin_trap();
  uint64_t seen = 0;
  const weaver::Status st =
      weaver::for_each_xyz_point(file.path(), grid, [&](uint64_t index, const float v[3]) {
        if (index >= n || !(v[1] > 0)) __builtin_trap();
        ++seen;
        return weaver::Status::Ok();
      });
  if (!st.ok() || seen != n) __builtin_trap();
  return 0;
}
