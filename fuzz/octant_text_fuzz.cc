// Octant text (import's input): any bytes are read line by line; every line
// is an octant or a one-line error, never a crash.
#include "fuzz_util.h"
#include "import/octant_text.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  weaver::fuzz::MemoryPath file(data, size);
  uint64_t last_line = 0;
  const weaver::Status st =
      weaver::read_octant_text(file.path(), [&](const weaver::Octant& o, uint64_t line) {
        if (line <= last_line || !weaver::octant_is_valid(o))
          __builtin_trap();  // lines go forward, octants valid
        last_line = line;
        return weaver::Status::Ok();
      });
  if (!st.ok() && st.message().find('\n') != std::string::npos) __builtin_trap();  // one line
  return 0;
}
