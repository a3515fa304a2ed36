// storage/manifest_file: the atomically committed, checksummed line files
// behind MANIFEST and the LSM's run list.
#include "storage/manifest_file.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "storage/checksum.h"
#include "test_util.h"

namespace weaver {
namespace {

using testing::slurp;

void spit(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
}

const std::vector<std::string> kLines = {"octants octants-3.bt", "nodes nodes-4.bt", "", "x y  z"};

TEST(ManifestFileTest, WhatIsWrittenIsReadBackAndNoTempIsLeft) {
  testing::TempDir dir;
  bool renamed = false;
  ASSERT_OK(write_manifest_file(dir.path(), "MANIFEST", "weaver-manifest 1", kLines, &renamed));
  EXPECT_TRUE(renamed);
  EXPECT_FALSE(std::filesystem::exists(dir.file("MANIFEST.tmp")));
  std::vector<std::string> lines;
  ASSERT_OK(read_manifest_file(dir.file("MANIFEST"), "weaver-manifest 1", &lines));
  EXPECT_EQ(lines, kLines);
  ASSERT_OK(write_manifest_file(dir.path(), "MANIFEST", "weaver-manifest 1", {"only"}));
  ASSERT_OK(read_manifest_file(dir.file("MANIFEST"), "weaver-manifest 1", &lines));
  EXPECT_EQ(lines, std::vector<std::string>{"only"});  // replaced whole
}

TEST(ManifestFileTest, DamagedFilesAreCorruptionNamingWhatIsWrong) {
  testing::TempDir dir;
  ASSERT_OK(write_manifest_file(dir.path(), "M", "hdr 1", kLines));
  const std::string good = slurp(dir.file("M"));
  const std::string body = good.substr(0, good.find("checksum "));
  struct Case {
    std::string bytes, message;
    bool needs_checksums;
  };
  std::string flipped = good;
  flipped[body.find("nodes")] = 'N';
  const std::vector<Case> cases = {
      {flipped, "checksum mismatch", true},
      {body, "truncated (no checksum line)", false},
      {good.substr(0, good.size() / 2), "", false},  // torn anywhere: never accepted
      {good + "extra\n", "bytes after the checksum line", false},
      {"hdr 2\n" + good.substr(good.find('\n') + 1), "unknown format 'hdr 2'", false},
      {"", "unknown format", false},
  };
  for (const Case& c : cases) {
    if (c.needs_checksums && !checksums_enforced()) continue;
    spit(dir.file("M"), c.bytes);
    std::vector<std::string> lines;
    const Status st = read_manifest_file(dir.file("M"), "hdr 1", &lines);
    EXPECT_TRUE(st.is_corruption()) << "'" << c.bytes << "': " << st.message();
    EXPECT_NE(st.message().find(c.message), std::string::npos) << st.message();
  }
  std::vector<std::string> lines;
  const Status missing = read_manifest_file(dir.file("absent"), "hdr 1", &lines);
  EXPECT_TRUE(missing.is_io_error()) << missing.message();
}

}  // namespace
}  // namespace weaver
