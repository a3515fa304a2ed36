// Corrupted pages, truncated files, bad headers and failing or short I/O.
#include <gtest/gtest.h>

#include <fstream>

#include "fault_file.h"
#include "storage/btree.h"
#include "storage/checksum.h"
#include "test_util.h"

namespace weaver {
namespace {

constexpr uint32_t kPage = 512;

TableOptions options() {
  TableOptions o;
  o.page_size = kPage;
  std::string err;
  o.schema = *RecordSchema::parse("a:u64", &err);
  return o;
}

class BTreeFaultTest : public ::testing::Test {
 protected:
  void SetUp() override { path_ = dir_.file("t.bt"); }

  void build(uint64_t n) {
    std::unique_ptr<File> f;
    ASSERT_OK(open_posix_file(path_, OpenMode::kCreateTruncate, &f));
    std::unique_ptr<BTree> t;
    ASSERT_OK(BTree::create(std::move(f), options(), 1 << 20, &t));
    for (uint64_t i = 0; i < n; ++i) ASSERT_OK(t->append(i * 2, reinterpret_cast<std::byte*>(&i)));
    ASSERT_OK(t->commit());
    pages_ = t->page_count();
  }

  Status open(std::unique_ptr<BTree>* t, uint64_t pool = 1 << 20) {
    std::unique_ptr<File> f;
    WEAVER_RETURN_IF_ERROR(open_posix_file(path_, OpenMode::kReadWrite, &f));
    return BTree::open(std::move(f), pool, t);
  }

  void flip_byte(uint64_t offset) {
    std::fstream f(path_, std::ios::in | std::ios::out | std::ios::binary);
    f.seekg(static_cast<std::streamoff>(offset));
    char c;
    f.read(&c, 1);
    c ^= 0x20;
    f.seekp(static_cast<std::streamoff>(offset));
    f.write(&c, 1);
  }

  // Reads every record through a full scan and every key through get().
  Status read_all(BTree& t) {
    BTreeCursor c;
    WEAVER_RETURN_IF_ERROR(t.seek_cursor(0, &c));
    while (c.valid()) WEAVER_RETURN_IF_ERROR(c.next());
    return t.check_invariants();
  }

  testing::TempDir dir_;
  std::string path_;
  uint32_t pages_ = 0;
};

TEST_F(BTreeFaultTest, CorruptedPageIsReportedWithFileAndPage) {
  build(5000);
  for (uint32_t page : {1u, pages_ / 2, pages_}) {
    build(5000);
    flip_byte(page::page_offset(page, kPage) + 100);
    std::unique_ptr<BTree> t;
    ASSERT_OK(open(&t));
    const Status st = read_all(*t);
    ASSERT_TRUE(st.is_corruption()) << st.to_string();
    EXPECT_NE(st.message().find(path_ + ": page " + std::to_string(page) + ": checksum"),
              std::string::npos)
        << st.message();
  }
}

TEST_F(BTreeFaultTest, EveryCorruptedByteIsCaughtNeverAWrongAnswer) {
  build(300);
  std::ifstream in(path_, std::ios::binary | std::ios::ate);
  const uint64_t size = static_cast<uint64_t>(in.tellg());
  for (uint64_t off = 0; off < size; off += 37) {
    build(300);
    flip_byte(off);
    std::unique_ptr<BTree> t;
    Status st = open(&t);
    if (st.ok()) st = read_all(*t);
    if (st.ok()) {  // only bytes outside any checksummed region may pass: none exist
      ADD_FAILURE() << "corruption at byte " << off << " went unnoticed";
    } else {
      EXPECT_TRUE(st.is_corruption()) << st.to_string();
    }
  }
}

// Found by fuzz/btree_file: a page whose checksum holds but whose entry count
// exceeds what the page can hold made searches read past the page.  Each
// page (the root, an internal page, then a leaf) gets a huge count and a
// checksum that matches it.
TEST_F(BTreeFaultTest, EntryCountBeyondThePageIsCorruptionNotAnOverrun) {
  build(5000);  // three levels of 4 KiB pages
  std::unique_ptr<BTree> probe;
  ASSERT_OK(open(&probe));
  ASSERT_GE(probe->height(), 2u);
  const uint32_t page_size = probe->options().page_size;
  probe.reset();
  for (uint32_t page_no = 0; page_no < pages_; ++page_no) {
    const std::string saved = dir_.file("saved.bt");
    std::filesystem::copy_file(path_, saved, std::filesystem::copy_options::overwrite_existing);
    {
      std::fstream f(path_, std::ios::in | std::ios::out | std::ios::binary);
      std::vector<std::byte> pg(page_size);
      const auto at =
          static_cast<std::streamoff>(page::kFileHeaderBytes + uint64_t{page_no} * page_size);
      f.seekg(at);
      f.read(reinterpret_cast<char*>(pg.data()), page_size);
      page::set_count(pg.data(), 65000);
      page::store32(pg.data() + page::kPgChecksum, checksum32(pg.data() + 4, page_size - 4));
      f.seekp(at);
      f.write(reinterpret_cast<const char*>(pg.data()), page_size);
    }
    // A full scan visits every page; the checker is not asked (it would
    // catch the count after the scan had read past the page).
    std::unique_ptr<BTree> t;
    Status st = open(&t);
    BTreeCursor c;
    if (st.ok()) st = t->seek_cursor(0, &c);
    while (st.ok() && c.valid()) st = c.next();
    EXPECT_TRUE(st.is_corruption()) << "page " << page_no << ": " << st.to_string();
    std::filesystem::copy_file(saved, path_, std::filesystem::copy_options::overwrite_existing);
  }
}

TEST_F(BTreeFaultTest, TruncatedFileIsReported) {
  build(5000);
  std::filesystem::resize_file(path_, page::page_offset(pages_, kPage) + 10);
  std::unique_ptr<BTree> t;
  Status st = open(&t);
  ASSERT_TRUE(st.is_corruption()) << st.to_string();
  EXPECT_NE(st.message().find("truncated"), std::string::npos);
  std::filesystem::resize_file(path_, 100);
  st = open(&t);
  ASSERT_TRUE(st.is_corruption()) << st.to_string();
  EXPECT_NE(st.message().find("truncated"), std::string::npos);
}

TEST_F(BTreeFaultTest, WrongMagicAndVersionAreReported) {
  build(10);
  flip_byte(page::kHdrMagic);
  std::unique_ptr<BTree> t;
  Status st = open(&t);
  EXPECT_NE(st.message().find("bad magic"), std::string::npos) << st.to_string();
  build(10);
  flip_byte(page::kHdrVersion);
  st = open(&t);
  ASSERT_TRUE(st.is_corruption());
  // The checksum covers the version, so a bare flip reads as a bad header.
  EXPECT_NE(st.message().find("header checksum"), std::string::npos) << st.to_string();
}

TEST_F(BTreeFaultTest, ShortTransfersAreCompleted) {
  auto base = std::unique_ptr<File>();
  ASSERT_OK(open_posix_file(path_, OpenMode::kCreateTruncate, &base));
  auto faulty = std::make_unique<testing::FaultFile>(std::move(base));
  faulty->max_transfer = 7;  // every read and write moves at most 7 bytes
  std::unique_ptr<BTree> t;
  ASSERT_OK(BTree::create(std::move(faulty), options(), 16 << 10, &t));
  for (uint64_t i = 0; i < 3000; ++i) {
    const uint64_t k = (i * 7919) % 3000;
    ASSERT_OK(t->put(k, reinterpret_cast<const std::byte*>(&k), nullptr));
  }
  ASSERT_OK(t->commit());
  ASSERT_OK(read_all(*t));  // reads back through 7-byte transfers too
  t.reset();
  ASSERT_OK(open(&t));
  ASSERT_EQ(t->size(), 3000u);
  ASSERT_OK(read_all(*t));
}

TEST_F(BTreeFaultTest, IoErrorsAreReturnedNotCrashes) {
  for (int64_t fail_after : {0, 1, 5, 20, 60}) {
    std::unique_ptr<File> base;
    ASSERT_OK(open_posix_file(path_, OpenMode::kCreateTruncate, &base));
    auto faulty = std::make_unique<testing::FaultFile>(std::move(base));
    testing::FaultFile* ff = faulty.get();
    std::unique_ptr<BTree> t;
    Status st = BTree::create(std::move(faulty), options(), 8 << 10, &t);
    ff->fail_writes_after = fail_after;
    for (uint64_t i = 0; st.ok() && i < 20000; ++i) {
      st = t ? t->put((i * 7919) % 20000, reinterpret_cast<const std::byte*>(&i), nullptr) : st;
    }
    if (st.ok()) st = t->commit();
    ASSERT_TRUE(st.is_io_error()) << fail_after << ": " << st.to_string();
    EXPECT_NE(st.message().find("injected write failure"), std::string::npos);
  }
  build(2000);
  std::unique_ptr<File> base;
  ASSERT_OK(open_posix_file(path_, OpenMode::kReadOnly, &base));
  auto faulty = std::make_unique<testing::FaultFile>(std::move(base));
  faulty->fail_reads_after = 3;
  std::unique_ptr<BTree> t;
  ASSERT_OK(BTree::open(std::move(faulty), 1 << 20, &t));
  const Status st = read_all(*t);
  ASSERT_TRUE(st.is_io_error()) << st.to_string();
}

TEST_F(BTreeFaultTest, SortedAppendPacksPagesWithinOnePointFivePercent) {
  std::unique_ptr<File> f;
  ASSERT_OK(open_posix_file(path_, OpenMode::kCreateTruncate, &f));
  TableOptions o;
  std::string err;
  o.schema = *RecordSchema::parse("a:u64,b:u64", &err);  // 16-byte payload, 4 KiB pages
  std::unique_ptr<BTree> t;
  ASSERT_OK(BTree::create(std::move(f), o, 4 << 20, &t));
  const uint64_t n = 500'000;
  std::byte payload[16] = {};
  for (uint64_t i = 0; i < n; ++i) ASSERT_OK(t->append(i * 3 + 1, payload));
  ASSERT_OK(t->commit());
  const double per_record = double(t->file_bytes()) / n;
  EXPECT_LT(per_record, 24 * 1.015) << per_record;
  const uint32_t leaves = static_cast<uint32_t>((n + 169) / 170);  // 170 records per leaf
  EXPECT_LT(t->page_count(), leaves + leaves / 100 + 3);
  ASSERT_OK(t->check_invariants());
}

}  // namespace
}  // namespace weaver
