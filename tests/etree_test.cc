// The etree reader against files the original etree library wrote, and what
// that library answered about them (tests/data/etree/README.md).
#include <gtest/gtest.h>

#include <fstream>
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

}  // namespace
}  // namespace weaver
