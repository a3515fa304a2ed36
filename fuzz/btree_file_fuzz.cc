// A whole B+tree table file: the file header, internal pages, plain and
// packed leaf pages.  Opened, checked, scanned and searched: every damage is
// a Status, never a crash or a read out of bounds.
#include "fuzz_util.h"
#include "storage/btree.h"

using namespace weaver;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::unique_ptr<BTree> t;
  if (!BTree::open(std::make_unique<fuzz::MemoryFile>(data, size), 64 << 10, &t).ok()) return 0;
  (void)t->check_invariants();
  BTreeCursor c;
  if (t->seek_cursor(0, &c).ok()) {
    for (int i = 0; i < 100000 && c.valid(); ++i) {
      if (!c.next().ok()) break;
    }
  }
  std::vector<std::byte> payload(t->payload_size() + 1);
  for (uint64_t key : {uint64_t{0}, uint64_t{1} << 40, ~uint64_t{0} >> 1, ~uint64_t{0}}) {
    bool found = false;
    uint64_t k = 0, rank = 0;
    (void)t->get(key, payload.data(), &found);
    (void)t->floor(key, &k, payload.data(), &found);
    (void)t->rank(key, &rank);
  }
  if (t->size() > 0) {
    uint64_t k = 0;
    (void)t->select(t->size() / 2, &k, payload.data());
  }
  return 0;
}
