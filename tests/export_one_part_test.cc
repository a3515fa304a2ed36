// raw --parts N and pvtu written one part at a time (export.h:
// export_parts_begin, export_one_part, export_parts_end; weaver-mpi export's
// path, each part's shared nodes found from its own elements by
// SharedNodes::build_part) against the whole-mesh export_mesh, whose shared
// nodes come from every element's corners: the same files, byte for byte, on
// generated octrees (non-cube block domains, holes, deep grading), by runs of
// element ids and by a stored partition of scattered parts.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <random>

#include "export/export.h"
#include "partition/partition.h"
#include "test_mesh.h"
#include "test_octrees.h"
#include "test_util.h"

namespace weaver {
namespace {

namespace fs = std::filesystem;

// Every file under root (or root itself), by its path relative to root.
std::map<std::string, std::string> tree(const std::string& root) {
  std::map<std::string, std::string> out;
  auto read = [](const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  if (fs::is_regular_file(root)) return {{"", read(root)}};
  for (const auto& e : fs::recursive_directory_iterator(root)) {
    out[fs::relative(e.path(), root).string() + (e.is_directory() ? "/" : "")] =
        e.is_directory() ? "" : read(e.path());
  }
  return out;
}

// export_mesh's files for o, and the part-at-a-time path's, under other names.
void expect_same_parts(const std::string& db, ExportOptions o, const testing::TempDir& dir) {
  const bool pvtu = o.format == ExportFormat::kPvtu;
  const std::string whole = dir.file(pvtu ? "whole.pvtu" : "whole");
  const std::string parted = dir.file(pvtu ? "parted.pvtu" : "parted");
  o.out = whole;
  ExportResult r;
  ASSERT_OK(export_mesh(db, o, &r));
  o.out = parted;
  ASSERT_OK(export_parts_begin(o));
  for (uint32_t p = o.parts; p-- > 0;) ASSERT_OK(export_one_part(db, o, p, &r));  // any order
  ASSERT_OK(export_parts_end(db, o, true, &r));
  std::map<std::string, std::string> a = tree(whole), b = tree(parted);
  if (pvtu) {  // the index names its own pieces' directory; the pieces themselves
    const auto pieces_a = tree(dir.file("whole")), pieces_b = tree(dir.file("parted"));
    ASSERT_EQ(pieces_a.size(), o.parts);
    for (uint32_t p = 0; p < o.parts; ++p) {
      const std::string n = "_" + std::to_string(p) + ".vtu";
      EXPECT_EQ(pieces_a.at("whole" + n), pieces_b.at("parted" + n)) << "piece " << p;
    }
    return;
  }
  ASSERT_EQ(a.size(), b.size());
  for (const auto& [name, bytes] : a) {
    ASSERT_TRUE(b.count(name)) << name;
    EXPECT_TRUE(bytes == b.at(name)) << name << " differs with " << o.parts << " parts";
  }
  fs::remove_all(whole);
  fs::remove_all(parted);
}

std::vector<std::vector<Octant>> octrees() {
  std::vector<std::vector<Octant>> out;
  for (uint64_t seed = 1; seed <= uint64_t(testing::scaled(3, 1)); ++seed) {
    out.push_back(testing::random_balanced(seed, 3, 2, 1, 2, 400, 8));            // non-cube
    out.push_back(reference::balance(testing::random_holed(seed, 400, 7, 0.7)));  // holes
    out.push_back(testing::random_balanced(seed + 10, 1, 1, 1, 0, 150, 11));      // deep
  }
  return out;
}

// A mesh of the first octree (a non-cube block domain) in dir.
std::string first_mesh(const testing::TempDir& dir) {
  return testing::build_mesh(testing::random_balanced(1, 3, 2, 1, 2, 400, 8), dir);
}

TEST(ExportOnePart, RawPartsAreTheWholeExportsByRunsAndByStoredParts) {
  for (const auto& leaves : octrees()) {
    testing::TempDir dir;
    const std::string db = testing::build_mesh(leaves, dir);
    ExportOptions o;
    o.format = ExportFormat::kRaw;
    for (uint32_t parts : {2u, 3u, 5u}) {
      o.parts = parts;
      ASSERT_NO_FATAL_FAILURE(expect_same_parts(db, o, dir));
    }
    // A stored partition of scattered parts: every corner is looked up.
    std::mt19937_64 rng(leaves.size());
    {
      std::ofstream f(dir.file("parts"));
      for (size_t i = 0; i < leaves.size(); ++i) f << rng() % 4 << "\n";
    }
    PartitionOptions po;
    po.parts = 4;
    po.method = PartitionOptions::Method::kGraph;
    po.part_file = dir.file("parts");
    PartitionReport report;
    ASSERT_OK(partition_mesh(db, po, &report));
    o.parts = 4;
    ASSERT_NO_FATAL_FAILURE(expect_same_parts(db, o, dir));
  }
}

TEST(ExportOnePart, PvtuPiecesAreTheWholeExports) {
  testing::TempDir dir;
  const std::string db = first_mesh(dir);
  ExportOptions o;
  o.format = ExportFormat::kPvtu;
  o.parts = 3;
  ASSERT_NO_FATAL_FAILURE(expect_same_parts(db, o, dir));
}

TEST(ExportOnePart, AFailedPartLeavesNoRawOutputAndNoPvtuIndex) {
  testing::TempDir dir;
  const std::string db = first_mesh(dir);
  ExportOptions o;
  o.format = ExportFormat::kRaw;
  o.parts = 2;
  o.out = dir.file("raw");
  ExportResult r;
  ASSERT_OK(export_parts_begin(o));
  ASSERT_OK(export_one_part(db, o, 0, &r));
  EXPECT_FALSE(export_one_part(db, o, 2, &r).ok());  // no such part
  ASSERT_OK(export_parts_end(db, o, false, &r));
  EXPECT_FALSE(fs::exists(o.out));
  EXPECT_FALSE(fs::exists(o.out + ".tmp"));
  o.format = ExportFormat::kPvtu;
  o.out = dir.file("p.pvtu");
  ASSERT_OK(export_parts_begin(o));
  ASSERT_OK(export_one_part(db, o, 1, &r));
  ASSERT_OK(export_parts_end(db, o, false, &r));
  EXPECT_FALSE(fs::exists(o.out));
  o.format = ExportFormat::kVtu;
  EXPECT_FALSE(export_parts_begin(o).ok());  // one part at a time is raw and pvtu's
}

}  // namespace
}  // namespace weaver
