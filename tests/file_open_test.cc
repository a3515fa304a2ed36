// storage/file: a reader's descriptor is opened without access-time updates
// where the owner may ask (this process owns the files it makes), reads
// what was written, and a missing file is -1 with ENOENT, which the
// database's snapshot relies on to notice a table a writer replaced.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cerrno>
#include <fstream>

#include "storage/file.h"
#include "test_util.h"

namespace weaver {
namespace {

TEST(FileOpen, AReaderOwnsNoAccessTimeUpdates) {
  testing::TempDir dir;
  const std::string path = dir.file("t.bin");
  std::ofstream(path) << "weaver";
  const int fd = open_for_reading(path);
  ASSERT_GE(fd, 0);
  const int flags = ::fcntl(fd, F_GETFL);
  EXPECT_EQ(flags & O_ACCMODE, O_RDONLY);
  EXPECT_NE(flags & O_NOATIME, 0);
  EXPECT_NE(::fcntl(fd, F_GETFD) & FD_CLOEXEC, 0);
  char buf[8] = {};
  EXPECT_EQ(::pread(fd, buf, sizeof buf, 0), 6);
  EXPECT_STREQ(buf, "weaver");
  ::close(fd);

  std::unique_ptr<File> f;
  ASSERT_OK(open_posix_file(path, OpenMode::kReadOnly, &f));
  char again[6];
  ASSERT_OK(read_fully(*f, 0, again, 6));
  EXPECT_EQ(std::string(again, 6), "weaver");
}

TEST(FileOpen, AMissingFileIsENOENT) {
  testing::TempDir dir;
  errno = 0;
  EXPECT_EQ(open_for_reading(dir.file("none")), -1);
  EXPECT_EQ(errno, ENOENT);
  std::unique_ptr<File> f;
  EXPECT_FALSE(open_posix_file(dir.file("none"), OpenMode::kReadOnly, &f).ok());
}

}  // namespace
}  // namespace weaver
