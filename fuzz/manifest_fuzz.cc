// The database MANIFEST: the checksummed file and its "table" lines, read
// by a reader opening the database.
#include "db/database.h"
#include "fuzz_util.h"
#include "storage/manifest_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string dir = weaver::fuzz::write_scratch_file("MANIFEST", data, size);
  std::vector<std::string> lines;
  (void)weaver::read_manifest_file(dir + "/MANIFEST", "weaver-db 1", &lines);
  std::unique_ptr<weaver::Database> db;
  (void)weaver::Database::open(dir, weaver::Database::Mode::kRead, false, &db);
  return 0;
}
