// The C API (include/weaver/weaver_c.h) over the C++ one.
#include <weaver/weaver.h>
#include <weaver/weaver_c.h>

#include <cstring>

using namespace weaver::api;

struct weaver_db {
  std::unique_ptr<MeshDatabase> db;
};
struct weaver_element_iter {
  ElementCursor cursor;
};
struct weaver_node_iter {
  NodeCursor cursor;
};

namespace {

void to_c(const Element& e, weaver_element* out) {
  std::memset(out, 0, sizeof *out);
  out->id = e.id;
  out->corner[0] = e.corner.x, out->corner[1] = e.corner.y, out->corner[2] = e.corner.z;
  out->edge = e.edge;
  out->level = e.level;
  for (int k = 0; k < 8; ++k) out->nodes[k] = e.nodes[k];
  out->vp = e.vp, out->vs = e.vs, out->rho = e.rho;
}

void to_c(const Node& n, weaver_node* out) {
  std::memset(out, 0, sizeof *out);
  out->id = n.id;
  out->at[0] = n.at.x, out->at[1] = n.at.y, out->at[2] = n.at.z;
  out->kind = int32_t(n.kind);
  out->anchor_count = n.anchor_count;
  for (int k = 0; k < 4; ++k) out->anchors[k] = n.anchors[k];
}

}  // namespace

extern "C" {

weaver_db* weaver_open(const char* path, uint64_t memory_bytes, char* error, size_t error_size) {
  return weaver_open_threads(path, memory_bytes, 1, error, error_size);
}

weaver_db* weaver_open_threads(const char* path, uint64_t memory_bytes, int threads, char* error,
                               size_t error_size) {
  std::string why;
  auto db = MeshDatabase::open(path != nullptr ? path : "", &why,
                               memory_bytes != 0 ? memory_bytes : uint64_t{256} << 20, threads);
  if (!db) {
    if (error != nullptr && error_size > 0) {
      std::strncpy(error, why.c_str(), error_size - 1);
      error[error_size - 1] = '\0';
    }
    return nullptr;
  }
  return new weaver_db{std::move(db)};
}

void weaver_close(weaver_db* db) { delete db; }
const char* weaver_last_error(const weaver_db* db) { return db->db->last_error().c_str(); }
uint64_t weaver_element_count(const weaver_db* db) { return db->db->element_count(); }
uint64_t weaver_node_count(const weaver_db* db) { return db->db->node_count(); }
int weaver_has_material(const weaver_db* db) { return db->db->has_material() ? 1 : 0; }

double weaver_units(const weaver_db* db, double origin[3]) {
  const Units u = db->db->units();
  if (origin != nullptr) std::memcpy(origin, u.origin_m.data(), 3 * sizeof(double));
  return u.tick_m;
}

int weaver_locate(weaver_db* db, const uint32_t* xyz, size_t n, weaver_hit* out) {
  std::vector<Point> p(n);
  for (size_t i = 0; i < n; ++i) p[i] = {xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]};
  std::vector<PointHit> h(n);
  if (!db->db->locate(p.data(), n, h.data())) return -1;
  for (size_t i = 0; i < n; ++i) {
    out[i] = weaver_hit{h[i].inside ? 1 : 0,
                        h[i].level,
                        h[i].element,
                        {h[i].corner.x, h[i].corner.y, h[i].corner.z},
                        h[i].edge,
                        h[i].vp,
                        h[i].vs,
                        h[i].rho};
  }
  return 0;
}

int weaver_element_get(weaver_db* db, uint64_t id, weaver_element* out) {
  Element e;
  if (!db->db->element(id, &e)) return -1;
  to_c(e, out);
  return 0;
}

int weaver_node_get(weaver_db* db, uint64_t id, weaver_node* out) {
  Node n;
  if (!db->db->node(id, &n)) return -1;
  to_c(n, out);
  return 0;
}

int weaver_node_at(weaver_db* db, const uint32_t xyz[3], int* found, uint64_t* id) {
  bool f = false;
  if (!db->db->node_at({xyz[0], xyz[1], xyz[2]}, &f, id)) return -1;
  *found = f ? 1 : 0;
  return 0;
}

int weaver_neighbors(weaver_db* db, uint64_t element, int kinds, weaver_neighbor* out,
                     size_t capacity, size_t* count) {
  std::vector<Neighbor> got;
  if (!db->db->neighbors(element, kinds & 1, kinds & 2, kinds & 4, &got)) return -1;
  *count = got.size();
  for (size_t i = 0; i < got.size() && i < capacity; ++i) {
    out[i] = weaver_neighbor{got[i].dx, got[i].dy, got[i].dz, 0, got[i].element};
  }
  return 0;
}

weaver_element_iter* weaver_elements(weaver_db* db, uint64_t first) {
  return new weaver_element_iter{db->db->elements(first)};
}

int weaver_element_next(weaver_element_iter* it, weaver_element* out) {
  Element e;
  if (it->cursor.next(&e)) return to_c(e, out), 1;
  return it->cursor.ok() ? 0 : -1;
}

void weaver_element_iter_free(weaver_element_iter* it) { delete it; }

weaver_node_iter* weaver_nodes(weaver_db* db) { return new weaver_node_iter{db->db->nodes()}; }

int weaver_node_next(weaver_node_iter* it, weaver_node* out) {
  Node n;
  if (it->cursor.next(&n)) return to_c(n, out), 1;
  return it->cursor.ok() ? 0 : -1;
}

void weaver_node_iter_free(weaver_node_iter* it) { delete it; }

}  // extern "C"
