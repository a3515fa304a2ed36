// The etree file (model/etree_file.h): headers, schema, B-tree pages, keys
// and payloads of the original etree library's format.
#include "fuzz_util.h"
#include "model/etree_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  weaver::fuzz::MemoryPath file(data, size);
  std::unique_ptr<weaver::EtreeFile> f;
  if (!weaver::EtreeFile::open(file.path(), &f).ok()) return 0;
  if (!f->start().ok()) return 0;
  // Walk every octant the file claims, reading every field of each; a
  // corrupt page must end the walk with an error, not a crash or a loop.
  for (uint64_t seen = 0; seen < (1u << 20); ++seen) {
    weaver::EtreeOctant o;
    bool done = false;
    if (!f->next(&o, &done).ok() || done) break;
    for (const weaver::EtreeField& field : f->info().fields) (void)f->read_field(o.payload, field);
  }
  return 0;
}
