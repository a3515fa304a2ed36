// The LSM's run list file (storage/lsm.h), read when a store is opened.
#include "fuzz_util.h"
#include "storage/lsm.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string dir = weaver::fuzz::write_scratch_file("LSM", data, size);
  std::unique_ptr<weaver::LsmTree> lsm;
  (void)weaver::LsmTree::open(dir, weaver::LsmOptions{}, &lsm);
  return 0;
}
