#include "partition/partition.h"

#include <algorithm>
#include <cstring>
#include <fstream>
#include <memory>

#include "db/database.h"
#include "db/partition_table.h"
#include "mesh/face_neighbors.h"
#include "mesh/mesh_reader.h"
#include "sort/external_sort.h"

namespace weaver {
namespace {

// Where the runs go: a table being built, or a vector (sfc, not stored).
struct RunSink {
  BTree* table = nullptr;
  std::vector<PartRun>* runs = nullptr;
  uint64_t count = 0;
  uint32_t last = UINT32_MAX;

  Status add(uint64_t id, uint32_t part) {
    if (part == last) return Status::Ok();
    last = part;
    ++count;
    if (runs != nullptr) runs->push_back({id, part});
    if (table == nullptr) return Status::Ok();
    std::byte p[4];
    std::memcpy(p, &part, 4);
    return table->append(id, p);
  }
};

int coarsest_level(Mesh& mesh) {
  LevelCounts levels{};
  if (!levels_from_metadata(mesh.octants().options().metadata, &levels)) return 0;
  for (int l = 0; l <= kMaxLevel; ++l) {
    if (levels[l] > 0) return l;
  }
  return 0;
}

// Contiguous ranges of ids, each near 1/parts of the total weight.
Status sfc_runs(Mesh& mesh, const PartitionOptions& o, RunSink& sink) {
  const int coarsest = coarsest_level(mesh);
  auto weight = [&](const Octant& e) -> uint64_t {
    if (o.weight == PartitionOptions::Weight::kNone) return 1;
    return uint64_t{1} << std::min(40, std::max(0, e.level - coarsest));
  };
  unsigned __int128 total = 0;
  ElementScan scan;
  WEAVER_RETURN_IF_ERROR(scan.start(mesh, 0, false));
  for (; scan.valid(); scan.next()) total += weight(scan.element().octant);
  WEAVER_RETURN_IF_ERROR(scan.status());
  unsigned __int128 before = 0;
  WEAVER_RETURN_IF_ERROR(scan.start(mesh, 0, false));
  for (; scan.valid(); scan.next()) {
    const uint64_t w = weight(scan.element().octant);
    // The part where the element's middle falls.
    const unsigned __int128 mid2 = 2 * before + w;
    const uint32_t part =
        uint32_t(std::min<unsigned __int128>(o.parts - 1, mid2 * o.parts / (2 * total)));
    WEAVER_RETURN_IF_ERROR(sink.add(scan.element().id, part));
    before += w;
    if (o.progress && scan.element().id % (1 << 16) == 0) {
      o.progress(scan.element().id,
                 0.5 * scan.element().id / std::max<uint64_t>(1, mesh.element_count()));
    }
  }
  return scan.status();
}

// A part per line, in element id order.
Status file_runs(Mesh& mesh, const PartitionOptions& o, RunSink& sink) {
  std::ifstream in(o.part_file);
  if (!in) return Status::IOError("cannot read " + o.part_file);
  uint64_t id = 0;
  std::string line;
  while (std::getline(in, line)) {
    char* end = nullptr;
    const unsigned long p = std::strtoul(line.c_str(), &end, 10);
    if (end == line.c_str() || p >= o.parts) {
      return Status::InvalidArgument(o.part_file + ":" + std::to_string(id + 1) + ": '" + line +
                                     "' is not a part below " + std::to_string(o.parts));
    }
    if (id >= mesh.element_count()) break;
    WEAVER_RETURN_IF_ERROR(sink.add(id++, uint32_t(p)));
  }
  if (id != mesh.element_count() || std::getline(in, line)) {
    return Status::InvalidArgument(o.part_file + ": " + std::to_string(id) + "+ lines for " +
                                   std::to_string(mesh.element_count()) + " elements");
  }
  return Status::Ok();
}

Status store_runs(const std::string& db_dir, Mesh& mesh, const PartitionOptions& o,
                  uint64_t pool_bytes, PartitionReport* report) {
  std::unique_ptr<Database> db;
  WEAVER_RETURN_IF_ERROR(Database::open(db_dir, Database::Mode::kWrite, false, &db));
  TableOptions t;
  t.key_kind = KeyKind::kNode;
  t.packed = true;
  std::string error;
  t.schema = *RecordSchema::parse(kPartitionSchema, &error);
  const bool sfc = o.method == PartitionOptions::Method::kSfc;
  t.metadata = std::string("method=") + (sfc ? "sfc" : "graph") +
               ";parts=" + std::to_string(o.parts) +
               ";weight=" + (o.weight == PartitionOptions::Weight::kLevel ? "level" : "none");
  std::unique_ptr<BTree> table;
  std::string file;
  WEAVER_RETURN_IF_ERROR(db->create_table(kPartitionTable, t, pool_bytes, &table, &file));
  RunSink sink{table.get()};
  const Status st = sfc ? sfc_runs(mesh, o, sink) : file_runs(mesh, o, sink);
  report->runs = sink.count;
  return db->publish(kPartitionTable, file, table, st);
}

// The report of a partition: one pass over the elements (their parts, face
// neighbours and corners), then the (node, part) pairs in node order.
Status report_of(Mesh& mesh, const PartMap& map, const PartitionMemory& memory,
                 const std::string& scratch, const ProgressFn& progress, PartitionReport* r) {
  r->parts.assign(map.parts(), PartStats{});
  ExternalSorter sorter(scratch, memory.node_sort);
  std::vector<FaceNeighbor> around;
  FaceFinder faces(mesh.octants());
  ElementScan scan;
  WEAVER_RETURN_IF_ERROR(scan.start(mesh, 0, true));
  const int coarsest = coarsest_level(mesh);
  for (; scan.valid(); scan.next()) {
    const MeshElement& e = scan.element();
    uint32_t p = 0;
    WEAVER_RETURN_IF_ERROR(map.part_of(e.id, &p));
    PartStats& s = r->parts[p];
    ++s.elements;
    s.weight += uint64_t{1} << std::min(40, std::max(0, e.octant.level - coarsest));
    around.clear();
    WEAVER_RETURN_IF_ERROR(faces.find(e.octant, &around));
    for (const FaceNeighbor& n : around) {
      uint32_t q = 0;
      WEAVER_RETURN_IF_ERROR(map.part_of(n.id, &q));
      if (q == p) continue;
      ++s.cut_faces;
      if (n.id > e.id) ++r->edge_cut;
    }
    for (uint64_t id : e.nodes) WEAVER_RETURN_IF_ERROR(sorter.add({id, p}));
    if (progress && e.id % (1 << 16) == 0) {
      progress(e.id, 0.5 + 0.4 * e.id / std::max<uint64_t>(1, mesh.element_count()));
    }
  }
  WEAVER_RETURN_IF_ERROR(scan.status());
  WEAVER_RETURN_IF_ERROR(sorter.finish());
  // Each node's parts arrive together, ascending: the first is the owner.
  uint64_t node = UINT64_MAX;
  uint32_t owner = 0, last = 0;
  int count = 0;
  auto close = [&] {
    if (node == UINT64_MAX) return;
    ++r->parts[owner].owned_nodes;
    if (count > 1) ++r->shared_nodes;
  };
  for (;;) {
    KeyTag kt;
    bool done = false;
    WEAVER_RETURN_IF_ERROR(sorter.next(&kt, &done));
    if (done) break;
    const uint32_t p = uint32_t(kt.tag);
    if (kt.key != node) {
      close();
      node = kt.key, owner = p, last = p, count = 1;
      continue;
    }
    if (p == last) continue;
    // A second (third, ...) part uses the node: each of them shares it.
    if (count == 1) ++r->parts[owner].shared_nodes;
    ++r->parts[p].shared_nodes;
    last = p;
    ++count;
  }
  close();
  return Status::Ok();
}

}  // namespace

PartitionMemory::PartitionMemory(MemoryBudget budget) : plan(budget) {
  // The elements are read in order, and the leaves across their faces
  // looked up: near in Z-order, so a modest pool holds them.
  octant_pool = plan.take("octant table pool", 1, 4, 64ull << 20);
  // Corner ids of each element, looked up by key.
  node_pool = plan.take("node table pool", 1, 4);
  // The partition table, written by sorted append: its right spine.
  table_pool = plan.take("partition table pool", 1, 16, 4ull << 20);
  // What the shares above do not hold: the face finder's decoded table
  // leaves (24 of them, 4.3 MB at 0.5 Hz) and the stored partition's map.
  plan.take("face finder's leaves, the partition map", 1, 8, 8ull << 20);
  // The report's (node, part) pairs, 8 an element, sorted out of core.
  node_sort = plan.take_rest("node-part sort");
}

Status partition_mesh(const std::string& db_dir, const PartitionOptions& o,
                      PartitionReport* report) {
  *report = PartitionReport{};
  if (o.parts < 1) return Status::InvalidArgument("--parts must be at least 1");
  const PartitionMemory memory(o.memory);
  std::unique_ptr<Mesh> mesh;
  WEAVER_RETURN_IF_ERROR(Mesh::open(db_dir, memory.octant_pool, memory.node_pool, &mesh));
  if (o.parts > mesh->element_count()) {
    return Status::InvalidArgument(std::to_string(o.parts) + " parts for " +
                                   std::to_string(mesh->element_count()) + " elements");
  }
  const std::string scratch = db_dir + "/tmp-partition-" + std::to_string(::getpid());
  if (!o.store) {
    if (o.method != PartitionOptions::Method::kSfc) {
      return Status::InvalidArgument("a graph partition is always stored");
    }
    std::vector<PartRun> runs;
    RunSink sink{nullptr, &runs};
    WEAVER_RETURN_IF_ERROR(sfc_runs(*mesh, o, sink));
    report->runs = sink.count;
    return report_of(*mesh, PartMap::of_runs(std::move(runs), o.parts), memory, scratch, o.progress,
                     report);
  }
  WEAVER_RETURN_IF_ERROR(store_runs(db_dir, *mesh, o, memory.table_pool, report));
  // The snapshot that made the partition is closed before the one that
  // reports it opens: the plan has room for one mesh's pools.
  mesh.reset();
  std::unique_ptr<Mesh> stored;  // a new snapshot, with the partition
  WEAVER_RETURN_IF_ERROR(Mesh::open(db_dir, memory.octant_pool, memory.node_pool, &stored));
  PartMap map;
  WEAVER_RETURN_IF_ERROR(stored->partition(&map));
  return report_of(*stored, map, memory, scratch, o.progress, report);
}

}  // namespace weaver
