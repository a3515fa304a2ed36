// weaver export: the CSV files against the reference mesh, row for row.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "db/database.h"
#include "db/node_table.h"
#include "db/octant_table.h"
#include "export/export_csv.h"
#include "extract/extract.h"
#include "gen/octree_gen.h"
#include "import/import.h"
#include "import/octant_text.h"
#include "query/mesh_query.h"
#include "reference/reference_mesh.h"
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

// Imports and extracts leaves into dir/db; returns the database path.
std::string build_mesh(const std::vector<Octant>& leaves, const testing::TempDir& dir) {
  const std::string db = dir.file("db"), text = dir.file("o.txt");
  EXPECT_OK(write_octant_text(text, leaves, ""));
  ImportResult ir;
  EXPECT_OK(import_octants(db, text, ImportOptions{}, &ir));
  ExtractResult er;
  EXPECT_OK(extract_mesh(db, ExtractOptions{}, &er));
  return db;
}

void check_export(const std::vector<Octant>& leaves, const testing::TempDir& dir) {
  const std::string db = build_mesh(leaves, dir);
  ExportOptions eo;
  eo.nodes_path = dir.file("nodes.csv");
  eo.elements_path = dir.file("elements.csv");
  ExportResult r;
  ASSERT_OK(export_csv(db, eo, &r));
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
}

TEST(Export, NeedsAnExtractedMesh) {
  testing::TempDir dir;
  std::ofstream(dir.file("o.txt")) << "0 0 0 0\n";
  ImportResult ir;
  ASSERT_OK(import_octants(dir.file("db"), dir.file("o.txt"), ImportOptions{}, &ir));
  ExportOptions eo;
  eo.nodes_path = dir.file("n.csv");
  ExportResult r;
  const Status st = export_csv(dir.file("db"), eo, &r);
  EXPECT_TRUE(st.is_not_found()) << st.to_string();
  EXPECT_NE(st.message().find("weaver extract"), std::string::npos);
}

}  // namespace
}  // namespace weaver

namespace weaver {
namespace {

TEST(MeshQuery, ElementsAndNodesByIdAndCoordinateMatchReference) {
  testing::TempDir dir;
  GenOptions g;
  g.kind = GenOptions::Kind::kSphere;
  g.level = 2;
  g.max_level = 5;
  g.radius = 0.27;
  std::vector<Octant> leaves;
  ASSERT_OK(generate_octree(g, &leaves));
  const std::string db = build_mesh(leaves, dir);
  std::unique_ptr<Database> d;
  std::unique_ptr<BTree> octants, nodes;
  ASSERT_OK(Database::open(db, Database::Mode::kRead, false, &d));
  ASSERT_OK(d->open_table(kOctantTable, 1 << 20, &octants));
  ASSERT_OK(d->open_table(kNodeTable, 1 << 20, &nodes));
  const reference::Mesh ref = reference::extract(leaves);
  for (uint64_t id = 0; id < ref.elements.size(); id += 7) {
    ElementInfo e;
    ASSERT_OK(element_by_id(*octants, nodes.get(), id, &e));
    ASSERT_EQ(e.octant, ref.elements[id]);
    ASSERT_EQ(e.nodes, ref.corners[id]);
  }
  for (uint64_t id = 0; id < ref.nodes.size(); id += 5) {
    NodeInfo n;
    ASSERT_OK(node_by_id(*nodes, id, &n));
    ASSERT_EQ(n.c, ref.nodes[id].c);
    ASSERT_EQ(n.kind, ref.nodes[id].kind);
    ASSERT_EQ(std::vector<uint64_t>(n.anchors.begin(), n.anchors.begin() + n.anchor_count),
              ref.nodes[id].anchors);
    bool found = false;
    NodeInfo at;
    ASSERT_OK(node_at(*nodes, n.c, &at, &found));
    ASSERT_TRUE(found);
    ASSERT_EQ(at.id, id);
  }
  bool found = true;
  NodeInfo at;
  ASSERT_OK(node_at(*nodes, {1, 1, 1}, &at, &found));
  EXPECT_FALSE(found);
  EXPECT_TRUE(node_at(*nodes, {kRootEdge + 1, 0, 0}, &at, &found).is_invalid_argument());
  ElementInfo e;
  EXPECT_TRUE(element_by_id(*octants, nodes.get(), ref.elements.size(), &e).is_invalid_argument());
}

}  // namespace
}  // namespace weaver
