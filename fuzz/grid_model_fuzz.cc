// The grid velocity model file: a header and float32 data.
#include "fuzz_util.h"
#include "model/grid_model.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  weaver::fuzz::MemoryPath file(data, size);
  std::unique_ptr<weaver::VelocityModel> model;
  if (weaver::load_grid_model(file.path(), &model).ok()) {
    // A loaded model answers everywhere, inside the grid and out.
    for (double c : {-1e9, 0.0, 1.5, 1e3, 1e9}) {
      const weaver::Material m = model->at(c, c, c);
      if (!(m.vs > 0)) __builtin_trap();
    }
  }
  return 0;
}
