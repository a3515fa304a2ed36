// The database MANIFEST: the checksummed file and its "table" lines, read
// by a reader opening the database.
#include <filesystem>
#include <fstream>

#include "db/database.h"
#include "fuzz_util.h"
#include "storage/manifest_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::string dir = [] {
    std::string tmpl = "/tmp/weaver-fuzz-manifest-XXXXXX";
    return std::string(::mkdtemp(tmpl.data()));
  }();
  {
    std::ofstream out(dir + "/MANIFEST", std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  std::vector<std::string> lines;
  (void)weaver::read_manifest_file(dir + "/MANIFEST", "weaver-db 1", &lines);
  std::unique_ptr<weaver::Database> db;
  (void)weaver::Database::open(dir, weaver::Database::Mode::kRead, false, &db);
  return 0;
}
