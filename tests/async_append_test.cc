// AsyncAppender builds, from batches handed over on another thread (or
// appended at once, without one), the same file a plain sorted append
// builds; an append error (keys out of order) comes back from a later
// append or from finish.
#include "db/async_append.h"

#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <random>

#include "storage/file.h"
#include "test_util.h"

namespace weaver {
namespace {

std::unique_ptr<BTree> new_table(const std::string& path) {
  std::unique_ptr<File> f;
  EXPECT_OK(open_posix_file(path, OpenMode::kCreateTruncate, &f));
  TableOptions o;
  std::string error;
  o.schema = *RecordSchema::parse("a:u32,b:u32", &error);
  o.packed = true;
  std::unique_ptr<BTree> t;
  EXPECT_OK(BTree::create(std::move(f), o, 1 << 20, &t));
  return t;
}

std::string bytes_of(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

TEST(AsyncAppend, BatchesBuildTheFileAPlainAppendBuildsWithOrWithoutAThread) {
  for (const bool own_thread : {true, false}) {
    SCOPED_TRACE(own_thread ? "on its own thread" : "on the caller's thread");
    testing::TempDir dir;
    std::mt19937_64 rng(5);
    std::vector<uint64_t> keys;
    uint64_t k = 0;
    for (int i = 0; i < 200000; ++i) keys.push_back(k += 1 + rng() % 1000);
    std::vector<std::byte> payloads(keys.size() * 8);
    for (auto& b : payloads) b = static_cast<std::byte>(rng());
    auto plain = new_table(dir.file("plain"));
    ASSERT_OK(plain->append_batch(keys.data(), payloads.data(), keys.size()));
    ASSERT_OK(plain->commit());
    auto threaded = new_table(dir.file("threaded"));
    {
      AsyncAppender appender(*threaded, own_thread);
      AsyncAppender::Batch batch;
      for (size_t i = 0; i < keys.size();) {
        const size_t n = std::min<size_t>(keys.size() - i, 1 + rng() % 5000);
        batch.keys.assign(keys.begin() + i, keys.begin() + i + n);
        batch.payloads.assign(payloads.begin() + 8 * i, payloads.begin() + 8 * (i + n));
        ASSERT_OK(appender.append(&batch));
        EXPECT_TRUE(batch.keys.empty() && batch.payloads.empty());
        i += n;
      }
      ASSERT_OK(appender.finish());
    }
    ASSERT_OK(threaded->commit());
    EXPECT_EQ(threaded->size(), keys.size());
    EXPECT_EQ(bytes_of(dir.file("threaded")), bytes_of(dir.file("plain")));
  }
}

TEST(AsyncAppend, AnAppendErrorComesBackToTheThreadThatHandsBatches) {
  for (const bool own_thread : {true, false}) {
    testing::TempDir dir;
    auto t = new_table(dir.file("t"));
    AsyncAppender appender(*t, own_thread);
    AsyncAppender::Batch batch;
    batch.keys = {10, 20};
    batch.payloads.resize(16);
    ASSERT_OK(appender.append(&batch));
    batch.keys = {5};  // out of order
    batch.payloads.resize(8);
    Status st = appender.append(&batch);
    for (int i = 0; i < 3 && st.ok(); ++i) {
      batch.keys = {uint64_t(100 + i)};
      batch.payloads.resize(8);
      st = appender.append(&batch);
    }
    const Status done = appender.finish();
    EXPECT_FALSE(done.ok());
    EXPECT_NE(done.message().find("out of order"), std::string::npos) << done.to_string();
  }
}

}  // namespace
}  // namespace weaver
