// One packed leaf page (storage/packed_leaf.h) read by every accessor, with a
// shape chosen by the first bytes: offsets are checked, never trusted.
#include <algorithm>
#include <cstring>
#include <vector>

#include "fuzz_util.h"
#include "storage/packed_leaf.h"

using namespace weaver;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 2) return 0;
  page::PackedShape shape;
  shape.key_kind = data[0] & 1 ? KeyKind::kOctant : KeyKind::kNode;
  const uint32_t widths[] = {1, 2, 4, 8};
  for (int f = 0; f < (data[1] & 3); ++f)
    shape.field_sizes.push_back(widths[(data[1] >> (2 + 2 * f)) & 3]);
  for (uint32_t w : shape.field_sizes) shape.payload += w;
  shape.page_size = 4096;  // as tables use
  std::vector<std::byte> pg(shape.page_size);
  std::memcpy(pg.data(), data + 2, std::min<size_t>(size - 2, pg.size()));
  page::PackedLeaf leaf;
  if (!leaf.open(pg.data(), shape)) return 0;
  std::vector<uint64_t> keys(leaf.size());
  std::vector<std::byte> vals(size_t{leaf.size()} * shape.payload + 1);
  if (!leaf.decode(keys.data(), vals.data())) return 0;
  // A damaged page may decode to keys out of order (the B+tree checker
  // reports that); only a sorted one must be searchable.
  const bool sorted = std::is_sorted(keys.begin(), keys.end()) &&
                      std::adjacent_find(keys.begin(), keys.end()) == keys.end();
  std::vector<std::byte> one(shape.payload + 1);
  for (uint32_t i = 0; i < leaf.size(); ++i) {
    uint64_t k = 0;
    if (!leaf.key(i, &k) || k != keys[i]) __builtin_trap();  // one answer, however asked
    leaf.payload(i, one.data());  // the payload decode gave, read on its own
    if (!std::equal(one.begin(), one.begin() + shape.payload,
                    vals.begin() + size_t{i} * shape.payload)) {
      __builtin_trap();
    }
    uint32_t pos = 0;
    if (leaf.bound(k, false, &pos) && sorted && pos != i) __builtin_trap();
  }
  return 0;
}
