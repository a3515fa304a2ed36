// The B+tree file header codec (storage/page_format.h): a round trip, and
// each damaged field refused by name, by the codec or by BTree::open.
#include <gtest/gtest.h>

#include <cstring>
#include <functional>
#include <memory>
#include <random>
#include <vector>

#include "storage/btree.h"
#include "storage/checksum.h"
#include "storage/file.h"
#include "storage/page_format.h"
#include "test_util.h"

namespace weaver {
namespace {

using Bytes = std::vector<std::byte>;

page::FileHeader sample_header(std::mt19937_64& rng) {
  page::FileHeader h;
  h.page_size = 1u << (7 + rng() % 10);
  h.payload_size = static_cast<uint32_t>(rng() % 64);
  h.key_kind = static_cast<uint8_t>(rng() % 2);
  h.leaf_format = static_cast<uint8_t>(rng() % 2);
  h.height = static_cast<uint32_t>(rng() % 10);
  h.root = static_cast<uint32_t>(rng());
  h.page_count = static_cast<uint32_t>(rng());
  h.free_head = static_cast<uint32_t>(rng());
  h.record_count = rng();
  h.schema_text = std::string(rng() % 40, 'a' + rng() % 26);
  h.metadata = std::string(rng() % 3000, static_cast<char>(rng()));  // any bytes
  return h;
}

Bytes encode(const page::FileHeader& h) {
  Bytes b(page::kFileHeaderBytes);
  page::encode_file_header(h, b.data());
  return b;
}

void reseal(Bytes& b) {
  page::store32(b.data() + page::kHdrChecksum, checksum32(b.data() + 4, b.size() - 4));
}

TEST(FileHeaderTest, EncodeThenDecodeGivesBackEveryField) {
  std::mt19937_64 rng(12);
  for (int i = 0; i < 200; ++i) {
    const page::FileHeader h = sample_header(rng);
    ASSERT_TRUE(page::file_header_fits(h.schema_text.size(), h.metadata.size()));
    const Bytes b = encode(h);
    page::FileHeader back;
    ASSERT_OK(page::decode_file_header(b.data(), "t.bt", &back));
    EXPECT_EQ(back, h);
    EXPECT_EQ(encode(back), b);  // and the bytes are a function of the fields
  }
}

TEST(FileHeaderTest, TheByteTableIsWhereTheFieldsGo) {
  page::FileHeader h;
  h.page_size = 4096;
  h.payload_size = 12;
  h.key_kind = 1;
  h.leaf_format = 1;
  h.height = 3;
  h.root = 77;
  h.page_count = 99;
  h.free_head = 5;
  h.record_count = 123456789012ull;
  h.schema_text = "vp:f32";
  h.metadata = "tick=1";
  const Bytes b = encode(h);
  const std::byte* p = b.data();
  EXPECT_EQ(page::load32(p + 4), page::kFormatVersion);
  EXPECT_EQ(std::memcmp(p + 8, "WVRBTREE", 8), 0);
  EXPECT_EQ(page::load32(p + 16), 4096u);
  EXPECT_EQ(page::load32(p + 20), 12u);
  EXPECT_EQ(static_cast<int>(p[24]), 1);
  EXPECT_EQ(static_cast<int>(p[25]), 1);
  EXPECT_EQ(page::load32(p + 28), 3u);
  EXPECT_EQ(page::load32(p + 32), 77u);
  EXPECT_EQ(page::load32(p + 36), 99u);
  EXPECT_EQ(page::load32(p + 40), 5u);
  EXPECT_EQ(page::load64(p + 48), 123456789012ull);
  EXPECT_EQ(page::load32(p + 56), 6u);
  EXPECT_EQ(page::load32(p + 60), 6u);
  EXPECT_EQ(std::memcmp(p + 64, "vp:f32tick=1", 12), 0);
  EXPECT_EQ(page::load32(p), checksum32(p + 4, page::kFileHeaderBytes - 4));
}

struct Damage {
  const char* field;
  std::function<void(Bytes&)> apply;  // then the checksum is made good again
  const char* message;                // in the error
};

TEST(FileHeaderTest, TheCodecRefusesEachDamagedFieldByName) {
  page::FileHeader h;
  h.page_size = 4096;
  h.schema_text = "vp:f32";
  const std::vector<Damage> damages = {
      {"magic", [](Bytes& b) { b[page::kHdrMagic + 3] = std::byte{'X'}; }, "bad magic"},
      {"version", [](Bytes& b) { page::store32(b.data() + page::kHdrVersion, 2); },
       "unsupported format version 2"},
      {"key kind", [](Bytes& b) { b[page::kHdrKeyKind] = std::byte{7}; }, "unknown key kind 7"},
      {"leaf format", [](Bytes& b) { b[page::kHdrLeafFormat] = std::byte{3}; },
       "unknown leaf format 3"},
      {"schema length", [](Bytes& b) { page::store32(b.data() + page::kHdrSchemaLen, 4033); },
       "lengths out of range"},
      {"metadata length", [](Bytes& b) { page::store32(b.data() + page::kHdrMetaLen, 1u << 31); },
       "lengths out of range"},
  };
  for (const Damage& d : damages) {
    Bytes b = encode(h);
    d.apply(b);
    reseal(b);
    page::FileHeader out;
    const Status st = page::decode_file_header(b.data(), "t.bt", &out);
    EXPECT_TRUE(st.is_corruption()) << d.field;
    EXPECT_NE(st.message().find(d.message), std::string::npos) << d.field << ": " << st.message();
    EXPECT_NE(st.message().find("t.bt"), std::string::npos) << d.field;
  }
  if (checksums_enforced()) {
    Bytes b = encode(h);
    b[page::kHdrRecordCount] ^= std::byte{1};  // not resealed
    page::FileHeader out;
    const Status st = page::decode_file_header(b.data(), "t.bt", &out);
    EXPECT_NE(st.message().find("header checksum mismatch"), std::string::npos) << st.message();
  }
}

// The fields whose meaning the tree checks: a table with a few records,
// its header rewritten (and resealed) with one field wrong.
TEST(FileHeaderTest, OpenRefusesHeadersWhoseFieldsDisagreeWithTheTree) {
  testing::TempDir dir;
  const std::string path = dir.file("t.bt");
  {
    std::unique_ptr<File> f;
    ASSERT_OK(open_posix_file(path, OpenMode::kCreateTruncate, &f));
    TableOptions o;
    std::string error;
    o.schema = *RecordSchema::parse("v:u32", &error);
    std::unique_ptr<BTree> t;
    ASSERT_OK(BTree::create(std::move(f), o, 1 << 20, &t));
    for (uint32_t k = 0; k < 5000; ++k)
      ASSERT_OK(t->put(k * 128, reinterpret_cast<std::byte*>(&k), nullptr));
    ASSERT_OK(t->commit());
  }
  Bytes good(page::kFileHeaderBytes);
  {
    std::unique_ptr<File> f;
    ASSERT_OK(open_posix_file(path, OpenMode::kReadOnly, &f));
    ASSERT_OK(read_fully(*f, 0, good.data(), good.size()));
  }
  page::FileHeader h;
  ASSERT_OK(page::decode_file_header(good.data(), path, &h));
  const std::vector<std::pair<std::function<void(page::FileHeader&)>, const char*>> cases = {
      {[](page::FileHeader& x) { x.page_size = 3000; }, "page size 3000"},
      {[](page::FileHeader& x) { x.payload_size = 8; }, "payload size disagrees"},
      {[](page::FileHeader& x) { x.schema_text = "v:q32"; }, "bad schema"},
      {[](page::FileHeader& x) { x.page_count += 1000; }, "file is truncated"},
      {[](page::FileHeader& x) { x.root = x.page_count + 1; }, "header fields out of range"},
      {[](page::FileHeader& x) { x.height = 0; }, "header fields out of range"},
      {[](page::FileHeader& x) { x.free_head = x.page_count + 1; }, "header fields out of range"},
  };
  for (const auto& [damage, message] : cases) {
    page::FileHeader bad = h;
    damage(bad);
    const Bytes b = encode(bad);
    std::unique_ptr<File> f;
    ASSERT_OK(open_posix_file(path, OpenMode::kReadWrite, &f));
    ASSERT_OK(write_fully(*f, 0, b.data(), b.size()));
    std::unique_ptr<BTree> t;
    const Status st = BTree::open(std::move(f), 1 << 20, &t);
    EXPECT_TRUE(st.is_corruption() || st.code() == Status::Code::kInvalidArgument) << message;
    EXPECT_NE(st.message().find(message), std::string::npos) << message << ": " << st.message();
  }
  std::unique_ptr<File> f;
  ASSERT_OK(open_posix_file(path, OpenMode::kReadWrite, &f));
  ASSERT_OK(write_fully(*f, 0, good.data(), good.size()));
  std::unique_ptr<BTree> t;
  ASSERT_OK(BTree::open(std::move(f), 1 << 20, &t));
  EXPECT_EQ(t->size(), 5000u);
  ASSERT_OK(t->check_invariants());
}

}  // namespace
}  // namespace weaver
