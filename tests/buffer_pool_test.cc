// BufferPool on its own: it holds no more frames than its budget (or its
// floor), writes evicted dirty pages back, never evicts a pinned page, and
// verifies every page it reads.
#include "storage/buffer_pool.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <vector>

#include "storage/checksum.h"
#include "storage/file.h"
#include "storage/page_format.h"
#include "test_util.h"

namespace weaver {
namespace {

constexpr uint32_t kPoolPage = 4096;

std::unique_ptr<File> new_file(const testing::TempDir& dir) {
  std::unique_ptr<File> f;
  EXPECT_TRUE(open_posix_file(dir.file("pool"), OpenMode::kCreateTruncate, &f).ok());
  return f;
}

uint64_t stamp(uint32_t page_no, int round) { return page_no * 1000003ull + round; }

// Creates pages 1..n, each stamped, unpinning as it goes.
void fill(BufferPool& pool, uint32_t n, int round) {
  for (uint32_t p = 1; p <= n; ++p) {
    Frame* f = nullptr;
    ASSERT_OK(pool.create(p, &f));
    page::store64(f->data + page::kPageHeaderBytes, stamp(p, round));
    pool.unpin(f);
  }
}

void expect_stamps(BufferPool& pool, uint32_t n, int round) {
  for (uint32_t p = 1; p <= n; ++p) {
    Frame* f = nullptr;
    ASSERT_OK(pool.fetch(p, &f));
    EXPECT_EQ(page::load64(f->data + page::kPageHeaderBytes), stamp(p, round)) << "page " << p;
    pool.unpin(f);
  }
}

TEST(BufferPoolTest, ThePoolStaysWithinItsBudgetAboveAFloor) {
  testing::TempDir dir;
  auto file = new_file(dir);
  for (const uint64_t budget : {1ull << 20, 3ull << 20, 64ull << 20}) {
    const BufferPool pool(file.get(), kPoolPage, budget);
    EXPECT_LE(pool.memory_bytes(), budget);
    EXPECT_GE(pool.memory_bytes(), budget * 9 / 10);  // and uses it
    EXPECT_GT(pool.frame_count(), BufferPool::kMinFrames);
  }
  for (const uint64_t tiny : {0ull, 4096ull, 300ull << 10}) {
    EXPECT_EQ(BufferPool(file.get(), kPoolPage, tiny).frame_count(), BufferPool::kMinFrames);
  }
}

TEST(BufferPoolTest, EvictedDirtyPagesAreWrittenBackAndReadAgain) {
  testing::TempDir dir;
  auto file = new_file(dir);
  const uint32_t pages = 5 * BufferPool::kMinFrames;  // five times what fits
  {
    BufferPool pool(file.get(), kPoolPage, 0);
    fill(pool, pages, 1);
    EXPECT_GE(pool.stats().pages_written, pages - pool.frame_count());
    expect_stamps(pool, pages, 1);  // evicted pages come back from the file
    EXPECT_GT(pool.stats().misses, 0u);
    ASSERT_OK(pool.flush());
  }
  BufferPool fresh(file.get(), kPoolPage, 0);  // nothing cached: all from disk
  expect_stamps(fresh, pages, 1);
  EXPECT_EQ(fresh.stats().pages_read, pages);
}

// A pool of several chunks of frames (allocated as the clock first reaches
// them; the last one part full): every frame's page is where data_of says,
// no two frames share bytes, and pages evicted from any chunk come back.
TEST(BufferPoolTest, FramesInEveryChunkHoldTheirOwnPages) {
  testing::TempDir dir;
  auto file = new_file(dir);
  BufferPool pool(file.get(), kPoolPage, 5ull << 20);
  ASSERT_GT(pool.frame_count(), 2 * (2ull << 20) / kPoolPage);  // three chunks or more
  const uint32_t pages = 3 * static_cast<uint32_t>(pool.frame_count());
  fill(pool, pages, 2);
  std::vector<std::byte*> seen;
  for (uint32_t p = pages - static_cast<uint32_t>(pool.frame_count()) + 1; p <= pages; ++p) {
    Frame* f = nullptr;
    ASSERT_OK(pool.fetch(p, &f));
    ASSERT_EQ(pool.data_of(f), f->data) << "page " << p;
    seen.push_back(f->data);
    pool.unpin(f);
  }
  std::sort(seen.begin(), seen.end());
  for (size_t i = 1; i < seen.size(); ++i) ASSERT_GE(seen[i] - seen[i - 1], kPoolPage);
  expect_stamps(pool, pages, 2);
  ASSERT_OK(pool.flush());
  BufferPool fresh(file.get(), kPoolPage, 5ull << 20);
  expect_stamps(fresh, pages, 2);
}

// Cached pages are found by a direct map for low page numbers and by a hash
// table above it (4 pages per frame): both must find what they hold, forget
// what they evict, and meet at the boundary.
TEST(BufferPoolTest, PagesAreFoundOnBothSidesOfTheDirectMap) {
  testing::TempDir dir;
  auto file = new_file(dir);
  BufferPool pool(file.get(), kPoolPage, 0);
  const uint32_t mapped = 4 * static_cast<uint32_t>(pool.frame_count());
  std::vector<uint32_t> pages;
  for (uint32_t p = 1; p <= 20; ++p) pages.push_back(p);
  for (uint32_t p = mapped - 10; p <= mapped + 10; ++p) pages.push_back(p);
  for (uint32_t p = 7 * mapped; p < 7 * mapped + 20; ++p) pages.push_back(p);
  ASSERT_LT(pages.size(), pool.frame_count());
  for (uint32_t p : pages) {
    Frame* f = nullptr;
    ASSERT_OK(pool.create(p, &f));
    page::store64(f->data + page::kPageHeaderBytes, stamp(p, 5));
    pool.unpin(f);
  }
  for (uint32_t p : pages) {  // all cached: hits, each in its own frame
    Frame* f = nullptr;
    ASSERT_OK(pool.fetch(p, &f));
    EXPECT_EQ(f->page_no, p);
    EXPECT_EQ(page::load64(f->data + page::kPageHeaderBytes), stamp(p, 5)) << "page " << p;
    pool.unpin(f);
  }
  EXPECT_EQ(pool.stats().misses, 0u);
  // Churn: a random walk over pages on both sides evicts and refetches; every
  // page read back holds its own stamp, whichever structure found it.
  uint64_t seed = 12345;
  std::vector<bool> written(8 * mapped, false);
  for (uint32_t p : pages) written[p] = true;
  for (int step = 0; step < 20000; ++step) {
    seed = seed * 6364136223846793005ull + 1442695040888963407ull;
    const uint32_t p = 1 + static_cast<uint32_t>((seed >> 33) % (8 * mapped - 1));
    Frame* f = nullptr;
    if (!written[p]) {
      ASSERT_OK(pool.create(p, &f));
      page::store64(f->data + page::kPageHeaderBytes, stamp(p, 5));
      written[p] = true;
    } else {
      ASSERT_OK(pool.fetch(p, &f));
      ASSERT_EQ(page::load64(f->data + page::kPageHeaderBytes), stamp(p, 5)) << "page " << p;
    }
    ASSERT_EQ(f->page_no, p);
    pool.unpin(f);
  }
  EXPECT_GT(pool.stats().hits, 0u);
  EXPECT_GT(pool.stats().misses, 0u);
}

TEST(BufferPoolTest, PinnedPagesAreNeverEvicted) {
  testing::TempDir dir;
  auto file = new_file(dir);
  BufferPool pool(file.get(), kPoolPage, 0);
  const uint32_t n = static_cast<uint32_t>(pool.frame_count());
  std::vector<Frame*> pinned;
  for (uint32_t p = 1; p <= n; ++p) {
    Frame* f = nullptr;
    ASSERT_OK(pool.create(p, &f));
    page::store64(f->data + page::kPageHeaderBytes, stamp(p, 2));
    pinned.push_back(f);
  }
  Frame* extra = nullptr;
  const Status st = pool.create(n + 1, &extra);
  EXPECT_EQ(st.code(), Status::Code::kBusy) << st.message();
  for (uint32_t p = 1; p <= n; ++p) {  // every pinned frame still holds its page
    EXPECT_EQ(pinned[p - 1]->page_no, p);
    EXPECT_EQ(page::load64(pinned[p - 1]->data + page::kPageHeaderBytes), stamp(p, 2));
  }
  pool.unpin(pinned[7]);  // one frame free: the next page takes exactly it
  ASSERT_OK(pool.create(n + 1, &extra));
  EXPECT_EQ(extra, pinned[7]);
  pool.unpin(extra);
  for (uint32_t p = 1; p <= n; ++p) {
    if (p != 8) pool.unpin(pinned[p - 1]);
  }
  ASSERT_OK(pool.flush());
  expect_stamps(pool, n, 2);
}

TEST(BufferPoolTest, ARecycledPageIsTheNextVictim) {
  testing::TempDir dir;
  auto file = new_file(dir);
  BufferPool pool(file.get(), kPoolPage, 0);
  const uint32_t n = static_cast<uint32_t>(pool.frame_count());
  fill(pool, n, 3);
  Frame* f = nullptr;
  ASSERT_OK(pool.fetch(5, &f));
  pool.unpin_recycle(f);
  Frame* g = nullptr;
  ASSERT_OK(pool.create(n + 1, &g));
  EXPECT_EQ(g, f);  // page 5's frame, not one chosen by the clock
  pool.unpin(g);
  ASSERT_OK(pool.flush());
  expect_stamps(pool, n, 3);  // page 5 was written back before its frame went
}

TEST(BufferPoolTest, ReadsAreVerified) {
  testing::TempDir dir;
  auto file = new_file(dir);
  {
    BufferPool pool(file.get(), kPoolPage, 0);
    fill(pool, 3, 4);
    ASSERT_OK(pool.flush());
  }
  // Page 2 gets page 3's bytes (a misdirected write): caught by number.
  std::vector<std::byte> buf(kPoolPage);
  ASSERT_OK(read_fully(*file, page::page_offset(3, kPoolPage), buf.data(), kPoolPage));
  ASSERT_OK(write_fully(*file, page::page_offset(2, kPoolPage), buf.data(), kPoolPage));
  // Page 1 gets a flipped bit: caught by the checksum.
  ASSERT_OK(read_fully(*file, page::page_offset(1, kPoolPage), buf.data(), kPoolPage));
  buf[100] ^= std::byte{4};
  ASSERT_OK(write_fully(*file, page::page_offset(1, kPoolPage), buf.data(), kPoolPage));
  BufferPool pool(file.get(), kPoolPage, 0);
  Frame* f = nullptr;
  Status st = pool.fetch(2, &f);
  EXPECT_TRUE(st.is_corruption());
  EXPECT_NE(st.message().find("holds the content of page 3"), std::string::npos) << st.message();
  if (checksums_enforced()) {
    st = pool.fetch(1, &f);
    EXPECT_NE(st.message().find("checksum mismatch"), std::string::npos) << st.message();
  }
  st = pool.fetch(9, &f);  // past the end of the file
  EXPECT_NE(st.message().find("truncated"), std::string::npos) << st.message();
  ASSERT_OK(pool.fetch(3, &f));
  pool.unpin(f);
}

}  // namespace
}  // namespace weaver
