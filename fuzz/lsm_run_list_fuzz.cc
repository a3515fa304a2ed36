// The LSM's run list file (storage/lsm.h), read when a store is opened.
#include <filesystem>
#include <fstream>

#include "fuzz_util.h"
#include "storage/lsm.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::string dir = [] {
    std::string tmpl = "/tmp/weaver-fuzz-lsm-XXXXXX";
    return std::string(::mkdtemp(tmpl.data()));
  }();
  {
    std::ofstream out(dir + "/LSM", std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  std::unique_ptr<weaver::LsmTree> lsm;
  (void)weaver::LsmTree::open(dir, weaver::LsmOptions{}, &lsm);
  return 0;
}
