// The 1-D layer table (model/layer_table.h): text lines of numbers.
#include <string>

#include "model/layer_table.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  weaver::LayerTable t;
  if (weaver::parse_layer_table(text, "fuzz", &t).ok()) {
    // An accepted table keeps its promises: tops from 0, increasing, and
    // positive velocities and density.
    if (t.layers.empty() || t.layers[0].top_m != 0) __builtin_trap();
    for (size_t i = 0; i < t.layers.size(); ++i) {
      if (i > 0 && !(t.layers[i].top_m > t.layers[i - 1].top_m)) __builtin_trap();
      for (int f = 0; f < 3; ++f) {
        if (!(t.layers[i].values[f] > 0)) __builtin_trap();
      }
    }
  }
  return 0;
}
