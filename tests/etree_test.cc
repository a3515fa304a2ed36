// The etree reader against files the original etree library wrote, and what
// that library answered about them (tests/data/etree/README.md).
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "model/etree_file.h"

namespace weaver {
namespace {

std::string fixture(const std::string& name) {
  return std::string(WEAVER_SOURCE_DIR) + "/tests/data/etree/" + name;
}

struct Recorded {
  uint32_t x, y, z;
  int level;
  bool leaf;
  std::vector<double> values;
};

std::vector<Recorded> read_octants(const std::string& name) {
  std::vector<Recorded> out;
  std::ifstream in(fixture(name));
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream s(line);
    Recorded r;
    char type;
    s >> r.x >> r.y >> r.z >> r.level >> type;
    r.leaf = type == 'L';
    for (double v; s >> v;) r.values.push_back(v);
    out.push_back(r);
  }
  return out;
}

std::vector<Recorded> scan(EtreeFile& f) {
  std::vector<Recorded> out;
  EXPECT_TRUE(f.start().ok());
  for (;;) {
    EtreeOctant o;
    bool done = false;
    const Status st = f.next(&o, &done);
    EXPECT_TRUE(st.ok()) << st.to_string();
    if (!st.ok() || done) break;
    Recorded r{o.x, o.y, o.z, o.level, o.leaf, {}};
    for (const EtreeField& fl : f.info().fields) r.values.push_back(f.read_field(o.payload, fl));
    out.push_back(r);
  }
  return out;
}

class EtreeFixture : public ::testing::TestWithParam<const char*> {};

TEST_P(EtreeFixture, EveryOctantMatchesTheLibrarysCursor) {
  const std::string name = GetParam();
  std::unique_ptr<EtreeFile> f;
  const Status st = EtreeFile::open(fixture(name + ".e"), &f);
  ASSERT_TRUE(st.ok()) << st.to_string();
  const std::vector<Recorded> want = read_octants(name + ".octants");
  const std::vector<Recorded> got = scan(*f);
  ASSERT_GT(want.size(), 1000u);
  ASSERT_EQ(got.size(), want.size());
  uint64_t leaves = 0;
  for (size_t i = 0; i < want.size(); ++i) {
    ASSERT_EQ(got[i].x, want[i].x) << "octant " << i;
    ASSERT_EQ(got[i].y, want[i].y) << "octant " << i;
    ASSERT_EQ(got[i].z, want[i].z) << "octant " << i;
    ASSERT_EQ(got[i].level, want[i].level) << "octant " << i;
    ASSERT_EQ(got[i].leaf, want[i].leaf) << "octant " << i;
    ASSERT_EQ(got[i].values.size(), want[i].values.size());
    for (size_t v = 0; v < want[i].values.size(); ++v) {
      // The library printed floats with 9 significant digits: exact.
      ASSERT_FLOAT_EQ(static_cast<float>(got[i].values[v]), static_cast<float>(want[i].values[v]))
          << "octant " << i << " field " << f->info().fields[v].name;
    }
    leaves += got[i].leaf;
  }
  EXPECT_EQ(f->info().leaves, leaves);
  EXPECT_EQ(f->info().leaves + f->info().interiors, got.size());
}

// etree_search's aggregate hit is the deepest octant holding the pixel; the
// reader's octants must give the library's answer at every recorded pixel.
TEST_P(EtreeFixture, AggregateHitsMatchTheLibrarysSearch) {
  const std::string name = GetParam();
  std::unique_ptr<EtreeFile> f;
  ASSERT_TRUE(EtreeFile::open(fixture(name + ".e"), &f).ok());
  const std::vector<Recorded> octants = scan(*f);
  std::ifstream in(fixture(name + ".search"));
  std::string line;
  int checked = 0;
  while (std::getline(in, line)) {
    std::istringstream s(line);
    uint32_t p[3], hit[3];
    int level;
    std::string arrow;
    s >> p[0] >> p[1] >> p[2] >> arrow >> hit[0] >> hit[1] >> hit[2] >> level;
    const Recorded* best = nullptr;
    for (const Recorded& o : octants) {
      const uint64_t edge = uint64_t{1} << (kEtreeMaxLevel - o.level);
      const bool in_it = p[0] - uint64_t{o.x} < edge && p[1] - uint64_t{o.y} < edge &&
                         p[2] - uint64_t{o.z} < edge && p[0] >= o.x && p[1] >= o.y && p[2] >= o.z;
      if (in_it && (!best || o.level > best->level)) best = &o;
    }
    ASSERT_NE(best, nullptr) << line;
    EXPECT_EQ(best->x, hit[0]) << line;
    EXPECT_EQ(best->y, hit[1]) << line;
    EXPECT_EQ(best->z, hit[2]) << line;
    EXPECT_EQ(best->level, level) << line;
    double v;
    for (size_t i = 0; s >> v; ++i) EXPECT_FLOAT_EQ(float(best->values[i]), float(v)) << line;
    ++checked;
  }
  EXPECT_EQ(checked, 2000);
}

INSTANTIATE_TEST_SUITE_P(LibraryFiles, EtreeFixture, ::testing::Values("cmu", "usgs"));

TEST(EtreeFile, SchemaAndMetadataAreRead) {
  std::unique_ptr<EtreeFile> f;
  ASSERT_TRUE(EtreeFile::open(fixture("usgs.e"), &f).ok());
  ASSERT_EQ(f->info().fields.size(), 8u);
  EXPECT_EQ(f->info().byte_order, 'L');
  ASSERT_NE(f->field("density"), nullptr);  // named "Density" in the file
  EXPECT_EQ(f->field("density")->offset, 8u);
  EXPECT_EQ(f->field("Zone")->type, "int16_t");
  EXPECT_EQ(f->field("Vs30"), nullptr);
  EXPECT_EQ(f->info().app_metadata.rfind("SCEC_CVM_V1|", 0), 0u);
}

class EtreeDamage : public ::testing::Test {
 protected:
  std::string write(const std::string& bytes) {
    const std::string path = ::testing::TempDir() + "damaged.e";
    std::ofstream(path, std::ios::binary) << bytes;
    return path;
  }
  std::string original() {
    std::ifstream in(fixture("cmu.e"), std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  }
  // Opening and scanning the whole file: the first error, or OK.
  Status read_all(const std::string& path) {
    std::unique_ptr<EtreeFile> f;
    WEAVER_RETURN_IF_ERROR(EtreeFile::open(path, &f));
    WEAVER_RETURN_IF_ERROR(f->start());
    for (bool done = false; !done;) {
      EtreeOctant o;
      WEAVER_RETURN_IF_ERROR(f->next(&o, &done));
    }
    return Status::Ok();
  }
};

TEST_F(EtreeDamage, EachDamageIsOneErrorNamingTheFile) {
  const std::string good = original();
  std::vector<std::pair<std::string, std::string>> cases = {
      {"empty", ""},
      {"truncated", good.substr(0, good.size() / 2)},
      {"not an etree", "X" + good.substr(1)},
      {"version", good.substr(0, 1) + std::string("\x02\0\0\0", 4) + good.substr(5)},
  };
  std::string page = good;
  page[4096 * 2 + 24] = 'q';  // a page's type
  cases.push_back({"page type", page});
  std::string schema = good;
  schema[0x134] = '9';  // the schema's field count
  cases.push_back({"schema", schema});
  for (const auto& [what, bytes] : cases) {
    const std::string path = write(bytes);
    const Status st = read_all(path);
    EXPECT_FALSE(st.ok()) << what;
    EXPECT_NE(st.message().find(path), std::string::npos) << what << ": " << st.message();
    EXPECT_EQ(st.message().find('\n'), std::string::npos) << what;
  }
}

// The etree library writes in its host's byte order, so its files here are
// all 'L'.  A 'B' file is made from each by turning every multi-byte number
// around where the format (etree_file.h) says the file's byte order rules:
// the headers' integers, the schema's order letter, the pages' sibling,
// count and child numbers, and each payload field; keys and text stay.
// It must read as the original, octant for octant, value for value.
std::string big_endian_copy(const std::string& little) {
  std::string b = little;
  auto le = [&](size_t at, int bytes) {
    uint64_t v = 0;
    for (int i = 0; i < bytes; ++i) v |= uint64_t{static_cast<unsigned char>(b[at + i])} << (8 * i);
    return v;
  };
  auto reverse = [&](size_t at, int bytes) {
    std::reverse(b.begin() + at, b.begin() + at + bytes);
  };
  const size_t bt = 273;  // the B-tree header
  const uint32_t page = uint32_t(le(bt + 1, 4)), key = uint32_t(le(bt + 21, 4)),
                 value = uint32_t(le(bt + 25, 4)), schema_bytes = uint32_t(le(bt + 29, 4));
  const uint64_t count = le(bt + 5, 8), root = le(bt + 13, 8);
  std::istringstream schema(b.substr(bt + 33, schema_bytes));
  std::string order;
  int fields = 0;
  schema >> order >> fields;
  std::vector<std::pair<uint32_t, uint32_t>> layout;  // offset, size
  for (int f = 0; f < fields; ++f) {
    std::string name, type;
    uint32_t size = 0, offset = 0;
    schema >> name >> type >> size >> offset;
    layout.push_back({offset, size});
  }
  for (uint64_t p = root; p < root + count; ++p) {
    const size_t at = size_t(p) * page;
    const uint32_t entries = uint32_t(le(at + 16, 4));
    const bool leaf = b[at + 24] == 'l';
    reverse(at, 8);
    reverse(at + 16, 4);
    for (uint32_t e = 0; e < entries; ++e) {
      const size_t entry = at + 25 + size_t(e) * (key + (leaf ? value : 8)) + key;
      if (!leaf) reverse(entry, 8);
      for (const auto& [offset, size] : layout) {
        if (leaf) reverse(entry + offset, int(size));
      }
    }
  }
  b[0] = b[bt] = b[bt + 33] = 'B';
  for (size_t at = 1; at < 273; at += 4) reverse(at, 4);
  reverse(bt + 1, 4), reverse(bt + 5, 8), reverse(bt + 13, 8);
  reverse(bt + 21, 4), reverse(bt + 25, 4), reverse(bt + 29, 4);
  return b;
}

TEST(EtreeFile, ABigEndianFileReadsAsItsLittleEndianOriginal) {
  for (const char* name : {"cmu", "usgs"}) {
    std::ifstream in(fixture(std::string(name) + ".e"), std::ios::binary);
    const std::string little(std::istreambuf_iterator<char>(in), {});
    const std::string path = ::testing::TempDir() + "etree_big_" + name + ".e";
    std::ofstream(path, std::ios::binary) << big_endian_copy(little);
    std::unique_ptr<EtreeFile> a, b;
    ASSERT_TRUE(EtreeFile::open(fixture(std::string(name) + ".e"), &a).ok());
    const Status st = EtreeFile::open(path, &b);
    ASSERT_TRUE(st.ok()) << st.to_string();
    EXPECT_EQ(b->info().byte_order, 'B');
    EXPECT_EQ(b->info().app_metadata, a->info().app_metadata);
    const std::vector<Recorded> want = scan(*a), got = scan(*b);
    ASSERT_EQ(got.size(), want.size()) << name;
    ASSERT_EQ(got.size(), read_octants(std::string(name) + ".octants").size());
    for (size_t i = 0; i < got.size(); ++i) {
      ASSERT_EQ(got[i].x, want[i].x) << name << " " << i;
      ASSERT_EQ(got[i].y, want[i].y);
      ASSERT_EQ(got[i].z, want[i].z);
      ASSERT_EQ(got[i].level, want[i].level);
      ASSERT_EQ(got[i].leaf, want[i].leaf);
      ASSERT_EQ(got[i].values, want[i].values) << name << " " << i;
    }
  }
}

}  // namespace
}  // namespace weaver
