// mesh_summary DB: counts of a weaver mesh through the C++ API, the way a
// solver's setup code would read it: elements per level, node kinds, the
// material range, and the element at the centre of the domain.
#include <weaver/weaver.h>

#include <algorithm>
#include <cstdio>
#include <map>

int main(int argc, char** argv) {
  using namespace weaver::api;
  if (argc != 2) {
    std::fprintf(stderr, "usage: mesh_summary DB\n");
    return 2;
  }
  std::string error;
  auto db = MeshDatabase::open(argv[1], &error);
  if (!db) {
    std::fprintf(stderr, "mesh_summary: %s\n", error.c_str());
    return 1;
  }
  std::printf("elements %llu\nnodes %llu\n", (unsigned long long)db->element_count(),
              (unsigned long long)db->node_count());
  std::map<int, unsigned long long> levels;
  uint32_t hi[3] = {0, 0, 0};
  float vs_min = 1e30f, vs_max = 0;
  ElementCursor elements = db->elements();
  for (Element e; elements.next(&e);) {
    ++levels[e.level];
    hi[0] = std::max(hi[0], e.corner.x + e.edge);
    hi[1] = std::max(hi[1], e.corner.y + e.edge);
    hi[2] = std::max(hi[2], e.corner.z + e.edge);
    vs_min = std::min(vs_min, e.vs), vs_max = std::max(vs_max, e.vs);
  }
  if (!elements.ok())
    return std::fprintf(stderr, "mesh_summary: %s\n", db->last_error().c_str()), 1;
  for (const auto& [level, count] : levels) std::printf("level %d %llu\n", level, count);
  unsigned long long kinds[3] = {0, 0, 0};
  if (db->has_mesh()) {
    NodeCursor nodes = db->nodes();
    for (Node n; nodes.next(&n);) ++kinds[int(n.kind)];
    if (!nodes.ok()) return std::fprintf(stderr, "mesh_summary: %s\n", db->last_error().c_str()), 1;
  }
  std::printf("anchored %llu\nedge %llu\nface %llu\n", kinds[0], kinds[1], kinds[2]);
  if (db->has_material()) std::printf("vs %g %g\n", vs_min, vs_max);
  PointHit hit;
  if (!db->locate({hi[0] / 2, hi[1] / 2, hi[2] / 2}, &hit)) return 1;
  std::printf("centre (%u %u %u) element %llu level %d\n", hi[0] / 2, hi[1] / 2, hi[2] / 2,
              (unsigned long long)hit.element, hit.level);
  return 0;
}
