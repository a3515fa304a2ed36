// weaver partition: the stored runs and the report against brute force on
// the reference mesh (face adjacency of every pair, node use by corners).
#include "partition/partition.h"

#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <random>
#include <set>

#include "db/database.h"
#include "db/partition_table.h"
#include "extract/extract.h"
#include "gen/octree_gen.h"
#include "import/import.h"
#include "import/octant_text.h"
#include "mesh/mesh_reader.h"
#include "reference/reference_mesh.h"
#include "test_mesh.h"
#include "test_octrees.h"
#include "test_util.h"

namespace weaver {
namespace {

using testing::build_mesh;

std::vector<std::vector<Octant>> meshes() {
  std::vector<std::vector<Octant>> out;
  for (uint64_t seed = 1; seed <= uint64_t(testing::scaled(4, 2)); ++seed) {
    GenOptions g;
    g.seed = seed;
    g.blocks[0] = 2 + seed % 2, g.blocks[1] = 3, g.blocks[2] = 1;
    g.block_level = 2;
    g.leaves = 300;
    g.max_level = 7;
    std::vector<Octant> leaves;
    EXPECT_OK(generate_octree(g, &leaves));
    out.push_back(reference::balance(leaves));
    out.push_back(reference::balance(testing::random_holed(seed, 300, 7, 0.7)));  // holes
  }
  return out;
}

// The parts of every element, read back from the stored table.
std::vector<uint32_t> stored_parts(const std::string& db, size_t elements) {
  std::unique_ptr<Mesh> mesh;
  EXPECT_OK(Mesh::open(db, 1 << 20, 1 << 20, &mesh));
  EXPECT_TRUE(mesh->has_partition());
  PartMap map;
  EXPECT_OK(mesh->partition(&map));
  std::vector<uint32_t> parts(elements);
  for (size_t i = 0; i < elements; ++i) EXPECT_OK(map.part_of(i, &parts[i]));
  return parts;
}

// The report of a partition, worked out from the reference mesh.
void expect_report(const reference::Mesh& ref, const std::vector<uint32_t>& part, uint32_t parts,
                   const PartitionReport& r) {
  ASSERT_EQ(r.parts.size(), parts);
  std::vector<PartStats> want(parts);
  uint64_t cut = 0, shared = 0;
  for (size_t i = 0; i < ref.elements.size(); ++i) {
    ++want[part[i]].elements;
    for (size_t j = 0; j < ref.elements.size(); ++j) {
      if (part[j] == part[i] || !reference::face_adjacent(ref.elements[i], ref.elements[j]))
        continue;
      ++want[part[i]].cut_faces;
      cut += j > i;
    }
  }
  std::vector<std::set<uint32_t>> users(ref.nodes.size());
  for (size_t i = 0; i < ref.elements.size(); ++i) {
    for (uint64_t n : ref.corners[i]) users[n].insert(part[i]);
  }
  for (const auto& u : users) {
    ++want[*u.begin()].owned_nodes;
    if (u.size() < 2) continue;
    ++shared;
    for (uint32_t p : u) ++want[p].shared_nodes;
  }
  EXPECT_EQ(r.edge_cut, cut);
  EXPECT_EQ(r.shared_nodes, shared);
  for (uint32_t p = 0; p < parts; ++p) {
    EXPECT_EQ(r.parts[p].elements, want[p].elements) << "part " << p;
    EXPECT_EQ(r.parts[p].owned_nodes, want[p].owned_nodes) << "part " << p;
    EXPECT_EQ(r.parts[p].shared_nodes, want[p].shared_nodes) << "part " << p;
    EXPECT_EQ(r.parts[p].cut_faces, want[p].cut_faces) << "part " << p;
  }
}

TEST(Partition, SfcRangesAreContiguousBalancedAndReportedExactly) {
  for (const auto& leaves : meshes()) {
    testing::TempDir dir;
    const std::string db = build_mesh(leaves, dir);
    const reference::Mesh ref = reference::extract(leaves);
    for (uint32_t parts : {1u, 3u, 7u}) {
      PartitionOptions o;
      o.parts = parts;
      PartitionReport r;
      ASSERT_OK(partition_mesh(db, o, &r));
      EXPECT_EQ(r.runs, parts);
      const std::vector<uint32_t> part = stored_parts(db, ref.elements.size());
      for (size_t i = 1; i < part.size(); ++i) ASSERT_LE(part[i - 1], part[i]);
      uint64_t least = UINT64_MAX, most = 0;
      for (const PartStats& s : r.parts) {
        least = std::min(least, s.elements), most = std::max(most, s.elements);
      }
      EXPECT_LE(most - least, 1u) << parts << " parts";
      ASSERT_NO_FATAL_FAILURE(expect_report(ref, part, parts, r));
    }
  }
}

// By level, each part's weight is within one (largest) element of the mean.
TEST(Partition, SfcByLevelWeightBalancesTheWeight) {
  const auto leaves = meshes()[0];
  testing::TempDir dir;
  const std::string db = build_mesh(leaves, dir);
  const reference::Mesh ref = reference::extract(leaves);
  PartitionOptions o;
  o.parts = 4;
  o.weight = PartitionOptions::Weight::kLevel;
  PartitionReport r;
  ASSERT_OK(partition_mesh(db, o, &r));
  // The weights rebuilt from the stored parts, not taken from the report.
  int coarsest = kMaxLevel, finest = 0;
  for (const Octant& l : ref.elements)
    coarsest = std::min<int>(coarsest, l.level), finest = std::max<int>(finest, l.level);
  ASSERT_LT(coarsest, finest) << "a graded mesh is needed to tell weights from counts";
  const std::vector<uint32_t> part = stored_parts(db, ref.elements.size());
  std::vector<uint64_t> weight(4), count(4);
  uint64_t total = 0;
  for (size_t i = 0; i < part.size(); ++i) {
    if (i > 0) {
      ASSERT_LE(part[i - 1], part[i]) << "sfc parts are runs of ids";
    }
    const uint64_t w = uint64_t{1} << (ref.elements[i].level - coarsest);
    weight[part[i]] += w, ++count[part[i]], total += w;
  }
  const uint64_t biggest = uint64_t{1} << (finest - coarsest);
  ASSERT_EQ(r.parts.size(), 4u);
  for (uint32_t p = 0; p < 4; ++p) {
    EXPECT_LE(std::llabs(int64_t(weight[p]) - int64_t(total / 4)), int64_t(biggest))
        << "part " << p << " weighs " << weight[p] << " of " << total;
    EXPECT_EQ(r.parts[p].weight, weight[p]) << "part " << p;
    EXPECT_EQ(r.parts[p].elements, count[p]) << "part " << p;
  }
  ASSERT_NO_FATAL_FAILURE(expect_report(ref, part, 4, r));
}

// A part file (gpmetis's format) becomes runs that give back every part;
// bad files are refused and leave no table; new octants drop the partition.
TEST(Partition, PartFilesAreStoredAsRunsAndCheckedAndDroppedWithTheOctants) {
  const auto leaves = meshes()[1];
  testing::TempDir dir;
  const std::string db = build_mesh(leaves, dir);
  const reference::Mesh ref = reference::extract(leaves);
  std::mt19937_64 rng(5);
  std::vector<uint32_t> want(ref.elements.size());
  {
    std::ofstream f(dir.file("parts"));
    for (auto& p : want) f << (p = uint32_t(rng() % 3 == 0 ? rng() % 5 : 2)) << "\n";
  }
  PartitionOptions o;
  o.parts = 5;
  o.method = PartitionOptions::Method::kGraph;
  o.part_file = dir.file("parts");
  PartitionReport r;
  ASSERT_OK(partition_mesh(db, o, &r));
  EXPECT_EQ(stored_parts(db, want.size()), want);
  ASSERT_NO_FATAL_FAILURE(expect_report(ref, want, 5, r));
  for (const char* bad : {"7\n", "x\n"}) {
    std::ofstream(dir.file("bad")) << bad;
    o.part_file = dir.file("bad");
    const Status st = partition_mesh(db, o, &r);
    EXPECT_FALSE(st.ok());
    EXPECT_NE(st.message().find("bad:1"), std::string::npos) << st.to_string();
  }
  {
    std::ofstream f(dir.file("short"));
    for (size_t i = 0; i + 1 < want.size(); ++i) f << "0\n";
  }
  o.part_file = dir.file("short");
  EXPECT_FALSE(partition_mesh(db, o, &r).ok());
  EXPECT_EQ(stored_parts(db, want.size()), want);  // the stored one is still there
  ImportResult ir;
  ASSERT_OK(import_octants(db, dir.file("o.txt"), ImportOptions{}, &ir));
  std::unique_ptr<Database> d;
  ASSERT_OK(Database::open(db, Database::Mode::kRead, false, &d));
  EXPECT_FALSE(d->has_table(kPartitionTable));
}

}  // namespace
}  // namespace weaver
