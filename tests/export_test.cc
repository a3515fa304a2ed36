// weaver export: the CSV files against the reference mesh, row for row.
#include "export/export.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <fstream>
#include <random>
#include <sstream>

#include "db/database.h"
#include "db/node_table.h"
#include "db/octant_table.h"
#include "extract/extract.h"
#include "gen/octree_gen.h"
#include "import/import.h"
#include "import/octant_text.h"
#include "mesh/face_neighbors.h"
#include "mesh/mesh_reader.h"
#include "reference/reference_mesh.h"
#include "test_mesh.h"
#include "test_octrees.h"
#include "test_util.h"

namespace weaver {
namespace {

std::vector<std::vector<std::string>> read_csv(const std::string& path, std::string* header) {
  std::ifstream in(path);
  std::getline(in, *header);
  std::vector<std::vector<std::string>> rows;
  std::string line;
  while (std::getline(in, line)) {
    std::vector<std::string> fields;
    std::stringstream ss(line);
    std::string f;
    while (std::getline(ss, f, ',')) fields.push_back(f);
    if (!line.empty() && line.back() == ',') fields.push_back("");
    rows.push_back(fields);
  }
  return rows;
}

const char* kind_name(NodeKind k) {
  return k == NodeKind::kAnchored ? "anchored" : k == NodeKind::kEdge ? "edge" : "face";
}

using testing::build_mesh;

void check_export(const std::vector<Octant>& leaves, const testing::TempDir& dir) {
  const std::string db = build_mesh(leaves, dir);
  ExportOptions eo;
  eo.nodes_path = dir.file("nodes.csv");
  eo.elements_path = dir.file("elements.csv");
  ExportResult r;
  ASSERT_OK(export_mesh(db, eo, &r));
  const reference::Mesh ref = reference::extract(leaves);
  std::string header;
  const auto nodes = read_csv(eo.nodes_path, &header);
  EXPECT_EQ(header, "id,x,y,z,kind,a0,a1,a2,a3");
  ASSERT_EQ(nodes.size(), ref.nodes.size());
  for (size_t i = 0; i < nodes.size(); ++i) {
    const auto& want = ref.nodes[i];
    std::vector<std::string> expect = {std::to_string(i), std::to_string(want.c.x),
                                       std::to_string(want.c.y), std::to_string(want.c.z),
                                       kind_name(want.kind)};
    for (size_t a = 0; a < 4; ++a) {
      expect.push_back(a < want.anchors.size() ? std::to_string(want.anchors[a]) : "");
    }
    ASSERT_EQ(nodes[i], expect) << "node row " << i;
  }
  const auto elements = read_csv(eo.elements_path, &header);
  EXPECT_EQ(header, "id,x,y,z,level,n0,n1,n2,n3,n4,n5,n6,n7");
  ASSERT_EQ(elements.size(), ref.elements.size());
  for (size_t i = 0; i < elements.size(); ++i) {
    const Octant& o = ref.elements[i];
    std::vector<std::string> expect = {std::to_string(i), std::to_string(o.x), std::to_string(o.y),
                                       std::to_string(o.z), std::to_string(o.level)};
    for (uint64_t n : ref.corners[i]) expect.push_back(std::to_string(n));
    ASSERT_EQ(elements[i], expect) << "element row " << i;
  }
}

// A part's nodes are visited by seeking one cursor forward (export's
// for_each_node): each stop is the node a lookup by id gives, whether the
// next id is the following one, a few ahead or far away; past the last
// node is an error.
TEST(Export, NodeScanSeeksToTheNodesALookupByIdFinds) {
  testing::TempDir dir;
  const std::string db =
      testing::build_mesh(reference::balance(testing::random_holed(4, 3000, 7, 0.8)), dir);
  std::unique_ptr<Mesh> mesh;
  ASSERT_OK(Mesh::open(db, 1 << 20, 1 << 20, &mesh));
  std::mt19937_64 rng(9);
  NodeScan scan;
  ASSERT_OK(scan.start(*mesh, true));
  uint64_t id = 0, seeks = 0;
  while (true) {
    const uint64_t gap = rng() % 8 == 0 ? rng() % 1000 : rng() % 4;  // near and far
    if (id + gap >= mesh->node_count()) break;
    id += gap;
    ASSERT_OK(scan.seek(id));
    MeshNode want;
    ASSERT_OK(mesh->node(id, true, &want));
    const MeshNode& got = scan.node();
    ASSERT_EQ(got.id, want.id);
    ASSERT_EQ(got.c, want.c) << "node " << id;
    ASSERT_EQ(got.kind, want.kind) << "node " << id;
    ASSERT_EQ(got.anchor_count, want.anchor_count) << "node " << id;
    for (int a = 0; a < want.anchor_count; ++a) ASSERT_EQ(got.anchors[a], want.anchors[a]);
    ++seeks;
  }
  EXPECT_GT(seeks, 100u);
  EXPECT_FALSE(scan.seek(mesh->node_count()).ok());
}

TEST(Export, CsvMatchesReferenceOnGradedAndNonCubeOctrees) {
  {
    testing::TempDir dir;
    GenOptions g;
    g.kind = GenOptions::Kind::kSphere;
    g.level = 1;
    g.max_level = 4;
    std::vector<Octant> leaves;
    ASSERT_OK(generate_octree(g, &leaves));
    ASSERT_NO_FATAL_FAILURE(check_export(leaves, dir));
  }
  for (uint64_t seed = 1; seed <= 5; ++seed) {
    testing::TempDir dir;
    GenOptions g;
    g.seed = seed;
    g.blocks[0] = 3, g.blocks[1] = 2, g.blocks[2] = 4;
    g.block_level = 2;
    g.leaves = 300;
    g.max_level = 7;
    std::vector<Octant> leaves;
    ASSERT_OK(generate_octree(g, &leaves));
    ASSERT_NO_FATAL_FAILURE(check_export(reference::balance(leaves), dir));
  }
  for (uint64_t seed = 1; seed <= 5; ++seed) {  // holes as fine as the leaves
    testing::TempDir dir;
    ASSERT_NO_FATAL_FAILURE(
        check_export(reference::balance(testing::random_holed(seed, 300, 7, 0.7)), dir));
  }
}

// Every leaf's face neighbours, found by floor and rank queries, are the
// leaves a brute-force test of every pair finds: on balanced meshes (1 or 4
// across a face), unbalanced octrees (any number) and non-cube domains.
TEST(Export, FaceNeighborsMatchBruteForce) {
  std::vector<std::vector<Octant>> cases;
  for (uint64_t seed = 1; seed <= uint64_t(testing::scaled(6, 2)); ++seed) {
    GenOptions g;
    g.seed = seed;
    g.blocks[0] = 3, g.blocks[1] = 1 + seed % 3, g.blocks[2] = 2;
    g.block_level = 2;
    g.leaves = uint64_t(testing::scaled(3000, 1000));  // several table leaves
    g.max_level = 8;
    std::vector<Octant> leaves;
    ASSERT_OK(generate_octree(g, &leaves));
    cases.push_back(leaves);  // unbalanced: steps of several levels
    cases.push_back(reference::balance(leaves));
    cases.push_back(testing::random_holed(seed, g.leaves / 3, 8, 0.7));  // holes, unbalanced
  }
  for (const auto& leaves : cases) {
    testing::TempDir dir;
    const std::string text = dir.file("o.txt");
    ASSERT_OK(write_octant_text(text, leaves, ""));
    ImportResult ir;
    ASSERT_OK(import_octants(dir.file("db"), text, ImportOptions{}, &ir));
    std::unique_ptr<Database> db;
    ASSERT_OK(Database::open(dir.file("db"), Database::Mode::kRead, false, &db));
    std::unique_ptr<BTree> t;
    ASSERT_OK(db->open_table(kOctantTable, 1 << 20, &t));
    std::vector<Octant> sorted = leaves;
    std::sort(sorted.begin(), sorted.end(),
              [](const Octant& a, const Octant& b) { return octant_key(a) < octant_key(b); });
    // One finder for all leaves in key order, as export uses it, and one
    // visiting them backwards (its cached leaves are never the next ones).
    FaceFinder forward(*t), backward(*t);
    for (size_t n = 0; n < 2 * sorted.size(); ++n) {
      const size_t i = n < sorted.size() ? n : 2 * sorted.size() - 1 - n;
      FaceFinder& faces = n < sorted.size() ? forward : backward;
      std::vector<FaceNeighbor> got;
      ASSERT_OK(faces.find(sorted[i], &got));
      std::vector<uint64_t> got_ids, want_ids;
      for (const FaceNeighbor& n : got) {
        got_ids.push_back(n.id);
        ASSERT_EQ(n.octant, sorted[n.id]);
      }
      for (size_t j = 0; j < sorted.size(); ++j) {
        if (j != i && reference::face_adjacent(sorted[i], sorted[j])) want_ids.push_back(j);
      }
      std::sort(got_ids.begin(), got_ids.end());
      ASSERT_EQ(got_ids, want_ids) << "leaf " << i;
    }
  }
}

// raw's arrays, read back as a solver would, are the reference mesh.
TEST(Export, RawArraysAreTheReferenceMesh) {
  testing::TempDir dir;
  GenOptions g;
  g.seed = 3;
  g.blocks[0] = 2, g.blocks[1] = 3, g.blocks[2] = 1;
  g.block_level = 2;
  g.leaves = 300;
  g.max_level = 7;
  std::vector<Octant> leaves;
  ASSERT_OK(generate_octree(g, &leaves));
  leaves = reference::balance(leaves);
  const std::string db = build_mesh(leaves, dir);
  ExportOptions eo;
  eo.format = ExportFormat::kRaw;
  eo.units = ExportUnits::kTicks;
  eo.out = dir.file("raw");
  ExportResult r;
  ASSERT_OK(export_mesh(db, eo, &r));
  const reference::Mesh ref = reference::extract(leaves);
  std::ifstream json(eo.out + "/mesh.json");
  const std::string text((std::istreambuf_iterator<char>(json)), {});
  std::ifstream bin(eo.out + "/mesh.bin", std::ios::binary);
  const std::string data((std::istreambuf_iterator<char>(bin)), {});
  // The offset of an array, from its entry in mesh.json.
  auto offset_of = [&](const std::string& name) {
    const size_t at = text.find("\"offset\": ", text.find("\"" + name + "\""));
    return std::stoull(text.substr(at + 10));
  };
  auto i64 = [&](const std::string& name, size_t i) {
    int64_t v;
    std::memcpy(&v, data.data() + offset_of(name) + 8 * i, 8);
    return v;
  };
  const size_t coords = offset_of("node_coords"), kinds = offset_of("node_kind");
  size_t dangling = 0;
  for (size_t i = 0; i < ref.nodes.size(); ++i) {
    uint32_t c[3];
    std::memcpy(c, data.data() + coords + 12 * i, 12);
    EXPECT_EQ((Coord{c[0], c[1], c[2]}), ref.nodes[i].c);
    EXPECT_EQ(uint8_t(data[kinds + i]), uint8_t(ref.nodes[i].kind));
    if (ref.nodes[i].kind == NodeKind::kAnchored) continue;
    EXPECT_EQ(i64("dangling_nodes", dangling), int64_t(i));
    for (size_t a = 0; a < 4; ++a) {
      const int64_t want = a < ref.nodes[i].anchors.size() ? int64_t(ref.nodes[i].anchors[a]) : -1;
      EXPECT_EQ(i64("dangling_anchors", 4 * dangling + a), want);
    }
    ++dangling;
  }
  for (size_t e = 0; e < ref.elements.size(); ++e) {
    for (int k = 0; k < 8; ++k) EXPECT_EQ(i64("element_nodes", 8 * e + k), ref.corners[e][k]);
    EXPECT_EQ(uint8_t(data[offset_of("element_level") + e]), ref.elements[e].level);
  }
  EXPECT_NE(text.find("\"dangling\": " + std::to_string(dangling)), std::string::npos);
}

// A failed export leaves no file behind; a device is written, not replaced;
// raw replaces an earlier export but no other directory.
TEST(Export, FailedWritersLeaveNoFileAndDevicesStayDevices) {
  testing::TempDir dir;
  GenOptions g;
  g.kind = GenOptions::Kind::kSphere;
  g.level = 1;
  g.max_level = 3;
  std::vector<Octant> leaves;
  ASSERT_OK(generate_octree(g, &leaves));
  const std::string db = build_mesh(leaves, dir);
  ExportOptions eo;
  ExportResult r;
  for (ExportFormat f : {ExportFormat::kVtu, ExportFormat::kMsh, ExportFormat::kMetis,
                         ExportFormat::kMetisMesh, ExportFormat::kRaw}) {
    eo.format = f;
    eo.out = dir.file("missing/dir/out");
    EXPECT_FALSE(export_mesh(db, eo, &r).ok());
    EXPECT_FALSE(std::ifstream(eo.out + ".tmp").good());
    eo.out = "/dev/null";
    if (f != ExportFormat::kRaw) {
      ASSERT_OK(export_mesh(db, eo, &r));
      struct stat st;
      ASSERT_EQ(::stat("/dev/null", &st), 0);
      ASSERT_TRUE(S_ISCHR(st.st_mode)) << "/dev/null was replaced";
    }
  }
  eo.format = ExportFormat::kRaw;
  eo.out = dir.file("other");
  ::mkdir(eo.out.c_str(), 0755);
  std::ofstream(eo.out + "/keep.txt") << "mine";
  const Status st = export_mesh(db, eo, &r);
  EXPECT_FALSE(st.ok());
  EXPECT_NE(st.message().find("not a raw export"), std::string::npos) << st.to_string();
  EXPECT_TRUE(std::ifstream(eo.out + "/keep.txt").good());
  eo.out = dir.file("raw");
  ASSERT_OK(export_mesh(db, eo, &r));
  ASSERT_OK(export_mesh(db, eo, &r));  // over the first one
  EXPECT_TRUE(std::ifstream(eo.out + "/mesh.json").good());
  EXPECT_FALSE(std::ifstream(eo.out + ".old/mesh.json").good());
  EXPECT_FALSE(std::ifstream(eo.out + ".tmp/mesh.json").good());
}

TEST(Export, NeedsAnExtractedMesh) {
  testing::TempDir dir;
  std::ofstream(dir.file("o.txt")) << "0 0 0 0\n";
  ImportResult ir;
  ASSERT_OK(import_octants(dir.file("db"), dir.file("o.txt"), ImportOptions{}, &ir));
  ExportOptions eo;
  eo.nodes_path = dir.file("n.csv");
  ExportResult r;
  const Status st = export_mesh(dir.file("db"), eo, &r);
  EXPECT_TRUE(st.is_not_found()) << st.to_string();
  EXPECT_NE(st.message().find("weaver extract"), std::string::npos);
}

}  // namespace
}  // namespace weaver
