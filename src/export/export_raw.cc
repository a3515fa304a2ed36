// raw: the paper's flat topology for solvers, as a directory of two files:
//   mesh.bin   little-endian arrays, each starting at a multiple of 64 bytes
//   mesh.json  for each array its dtype (numpy's spelling), shape, byte
//              offset in mesh.bin and units, and the mesh's counts and units
// Arrays:
//   node_coords       (nodes, 3)     <f8 metres, or <u4 ticks with --units ticks
//   node_kind         (nodes,)       |u1  0 anchored, 1 edge, 2 face
//   element_nodes     (elements, 8)  <i8  node ids of corners 0..7, x fastest
//   element_level     (elements,)    |u1
//   element_material  (elements, 3)  <f4  vp, vs, rho (when the mesh has them)
//   element_q         (elements, 2)  <f4  qp, qs (when its material has them)
//   element_solid_fraction (elements,) <f4  the share of the element below the
//                                         ground (a mesh built with --surface)
//   boundary_faces    (boundary, 3)  <i8  element id, face (0-5: x-, x+, y-, y+, z- up,
//                                         z+ down), part (0 whole, 1-4 a quarter):
//                                         db/boundary_table.h (when the mesh has one)
//   boundary_kind     (boundary,)    |u1  0 domain side (absorbing), 1 free surface
//   dangling_nodes    (dangling,)    <i8  the node ids of dangling nodes
//   dangling_anchors  (dangling, 4)  <i8  their anchors' ids, -1 past 2 for edges
//   node_global_id    (nodes,)       <i8  with --box: the node's id in the whole mesh
//   element_global_id (elements,)    <i8  with --box: the element's id in the whole mesh
//   node_lonlat       (nodes, 2)     <f8  longitude, latitude (WGS84 degrees), when the
//                                         mesh is georeferenced (mesh.json's "geo" says how)
// With --box, node ids in the arrays are local: positions in node_coords.
// numpy: np.memmap(dir + "/mesh.bin", dtype, "r", offset, tuple(shape)).
// The directory is built as OUT.tmp and renamed to OUT when complete; an
// existing OUT is replaced only if it holds a mesh.json (an earlier export).
#include <sys/stat.h>

#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "export/boundary_faces.h"
#include "export/shared_nodes.h"
#include "export/writers.h"

namespace weaver {
namespace {

namespace fs = std::filesystem;

struct Array {
  std::string name, dtype;
  uint64_t rows;
  int cols;  // 0: one-dimensional
  uint64_t item_bytes;
  const char* units;    // "" for none
  bool always = false;  // in mesh.json even with no rows
  uint64_t offset = 0;
  uint64_t bytes() const { return rows * std::max(cols, 1) * item_bytes; }
};

enum : int {
  kCoords,
  kKind,
  kElementNodes,
  kLevel,
  kMaterial,
  kDangling,
  kAnchors,
  kNodeGlobal,
  kElementGlobal,
  kSharedNodes,
  kSharedParts,
  kLonLat,
  kQ,
  kSolid,
  kBoundaryFaces,
  kBoundaryKind,
  kArrays
};

// Arrays with no rows (no material, the whole mesh's global ids) are left
// out of mesh.json.
// shared: the part's (node, other part) pairs, or -1 outside a partition.
std::vector<Array> layout(uint64_t n, uint64_t e, uint64_t d, bool ticks, bool material, bool q,
                          bool selected, int64_t shared, bool geo, bool solid, uint64_t b) {
  std::vector<Array> a = {
      {"node_coords", ticks ? "<u4" : "<f8", n, 3, ticks ? 4u : 8u, ticks ? "ticks" : "m"},
      {"node_kind", "|u1", n, 0, 1, ""},
      {"element_nodes", "<i8", e, 8, 8, ""},
      {"element_level", "|u1", e, 0, 1, ""},
      {"element_material", "<f4", material ? e : 0, 3, 4, "m/s, m/s, kg/m^3"},
      {"dangling_nodes", "<i8", d, 0, 8, ""},
      {"dangling_anchors", "<i8", d, 4, 8, ""},
      {"node_global_id", "<i8", selected ? n : 0, 0, 8, ""},
      {"element_global_id", "<i8", selected ? e : 0, 0, 8, ""},
      {"shared_nodes", "<i8", uint64_t(std::max<int64_t>(shared, 0)), 0, 8, ""},
      {"shared_parts", "<i4", uint64_t(std::max<int64_t>(shared, 0)), 0, 4, ""},
      {"node_lonlat", "<f8", geo ? n : 0, 2, 8, "degrees"},
      {"element_q", "<f4", q ? e : 0, 2, 4, ""},
      {"element_solid_fraction", "<f4", solid ? e : 0, 0, 4, ""},
      {"boundary_faces", "<i8", b, 3, 8, ""},
      {"boundary_kind", "|u1", b, 0, 1, ""}};
  a[kDangling].always = a[kAnchors].always = true;
  a[kSharedNodes].always = a[kSharedParts].always = shared >= 0;
  uint64_t at = 0;
  for (Array& x : a) x.offset = at, at = (at + x.bytes() + 63) / 64 * 64;
  return a;
}

std::string number(double v) {
  std::string s;
  char buf[32];
  s.assign(buf, std::to_chars(buf, buf + sizeof buf, v).ptr);
  return s;
}

std::string json(const std::vector<Array>& arrays, const ExportJob& job, uint64_t dangling) {
  const Units& u = job.mesh.units();
  std::string s = "{\n  \"format\": \"weaver-raw\",\n  \"version\": 1,\n";
  s += "  \"data_file\": \"mesh.bin\",\n  \"byte_order\": \"little\",\n";
  s += "  \"nodes\": " + std::to_string(job.node_count()) + ",\n";
  s += "  \"elements\": " + std::to_string(job.element_count()) + ",\n";
  s += "  \"dangling\": " + std::to_string(dangling) + ",\n";
  s += std::string("  \"units\": \"") + job.unit_name() + "\",\n";
  s += "  \"tick_m\": " + number(u.tick_m) + ",\n  \"origin_m\": [" + number(u.origin_m[0]) + ", " +
       number(u.origin_m[1]) + ", " + number(u.origin_m[2]) + "],\n";
  if (job.mesh.has_ground()) {
    s += "  \"top_elevation_m\": " + number(job.mesh.top_elevation()) + ",\n";
  }
  if (job.options.z_up) s += "  \"z_up\": true,\n";
  if (!u.geo.empty()) s += "  \"geo\": \"" + u.geo + "\",\n";
  s += "  \"corner_order\": \"corner k at (x + s*(k&1), y + s*((k>>1)&1), z + s*((k>>2)&1))\",\n";
  s += "  \"node_kinds\": [\"anchored\", \"edge\", \"face\"],\n  \"arrays\": {";
  bool first = true;
  for (int i = 0; i < kArrays; ++i) {
    const Array& a = arrays[i];
    if (a.rows == 0 && !a.always) continue;
    s += first ? "\n" : ",\n";
    first = false;
    s += "    \"" + a.name + "\": {\"dtype\": \"" + a.dtype + "\", \"shape\": [" +
         std::to_string(a.rows) + (a.cols > 0 ? ", " + std::to_string(a.cols) : "") +
         "], \"offset\": " + std::to_string(a.offset) + ", \"units\": \"" + a.units + "\"}";
  }
  return s + "\n  }\n}\n";
}

// Dangling nodes of the selection: a pass that leaves the counts as they were.
Status count_dangling(ExportJob& job, uint64_t* d) {
  if (job.local != nullptr && job.local->knows_dangling()) {  // counted as it was built
    *d = job.local->dangling_count();
    return Status::Ok();
  }
  const ExportResult before = *job.result;
  const uint64_t done = job.done;
  *d = 0;
  const Status st = for_each_node(job, false, [d](const MeshNode& n) {
    *d += n.kind != NodeKind::kAnchored;
    return Status::Ok();
  });
  *job.result = before;
  job.done = done;
  return st;
}

Status write_nodes(ExportJob& job, std::vector<Section>& out, const GeoTransform* geo) {
  const bool ticks = job.options.units == ExportUnits::kTicks;
  const bool selected = !job.sel.whole();
  uint64_t local = 0;
  return for_each_node(job, true, [&](const MeshNode& n) {
    if (geo) {
      double ll[2];
      job.lon_lat(*geo, n.c, &ll[0], &ll[1]);
      WEAVER_RETURN_IF_ERROR(out[kLonLat].put(ll, sizeof ll));
    }
    if (ticks) {
      const uint32_t p[3] = {n.c.x, n.c.y, n.c.z};
      WEAVER_RETURN_IF_ERROR(out[kCoords].put(p, sizeof p));
    } else {
      const double p[3] = {job.coord(0, n.c.x), job.coord(1, n.c.y), job.coord(2, n.c.z)};
      WEAVER_RETURN_IF_ERROR(out[kCoords].put(p, sizeof p));
    }
    WEAVER_RETURN_IF_ERROR(out[kKind].value(uint8_t(n.kind)));
    if (selected) WEAVER_RETURN_IF_ERROR(out[kNodeGlobal].value(int64_t(n.id)));
    if (n.kind != NodeKind::kAnchored) {
      WEAVER_RETURN_IF_ERROR(out[kDangling].value(int64_t(local)));
      int64_t a[4] = {-1, -1, -1, -1};
      for (int i = 0; i < n.anchor_count; ++i) {
        uint64_t id = 0;
        WEAVER_RETURN_IF_ERROR(job.local->local_id(n.anchors[i], &id));
        a[i] = int64_t(id);
      }
      WEAVER_RETURN_IF_ERROR(out[kAnchors].put(a, sizeof a));
    }
    ++local;
    return Status::Ok();
  });
}

Status write_elements(ExportJob& job, std::vector<Section>& out, bool material, bool q) {
  const bool selected = !job.sel.whole();
  return for_each_element(job, true, [&](const MeshElement& e) {
    int64_t ids[8];
    for (int k = 0; k < 8; ++k) ids[k] = int64_t(e.nodes[k]);
    WEAVER_RETURN_IF_ERROR(out[kElementNodes].put(ids, sizeof ids));
    WEAVER_RETURN_IF_ERROR(out[kLevel].value(uint8_t(e.octant.level)));
    if (selected) WEAVER_RETURN_IF_ERROR(out[kElementGlobal].value(int64_t(e.id)));
    if (q) {
      const float f[2] = {e.qp, e.qs};
      WEAVER_RETURN_IF_ERROR(out[kQ].put(f, sizeof f));
    }
    if (job.mesh.has_solid()) WEAVER_RETURN_IF_ERROR(out[kSolid].value(e.solid));
    if (!material) return Status::Ok();
    const float m[3] = {e.vp, e.vs, e.rho};
    return out[kMaterial].put(m, sizeof m);
  });
}

Status write_text_file(const std::string& path, const std::string& text) {
  OutputFile f(path);
  WEAVER_RETURN_IF_ERROR(f.open());
  WEAVER_RETURN_IF_ERROR(f.write_at(0, text.data(), text.size()));
  return f.finish();
}

// The part's shared pairs, in local node ids.
Status write_shared(ExportJob& job, SharedNodes& shared, std::vector<Section>& out) {
  const uint32_t p = job.sel.part;
  for (uint64_t i = 0; i < shared.count(p); ++i) {
    uint64_t node = 0, local = 0;
    uint32_t other = 0;
    WEAVER_RETURN_IF_ERROR(shared.next(p, &node, &other));
    WEAVER_RETURN_IF_ERROR(job.local->local_id(node, &local));
    WEAVER_RETURN_IF_ERROR(out[kSharedNodes].value(int64_t(local)));
    WEAVER_RETURN_IF_ERROR(out[kSharedParts].value(int32_t(other)));
  }
  return Status::Ok();
}

// Moves the finished tmp directory to out, replacing an earlier raw export
// there (one with a mesh.json or parts.json), and nothing else.
Status install_dir(const std::string& tmp, const std::string& out) {
  std::error_code ec;
  const std::string old = out + ".old";
  if (fs::exists(out, ec)) {
    if (!fs::is_directory(out, ec) ||
        !(fs::exists(out + "/mesh.json", ec) || fs::exists(out + "/parts.json", ec))) {
      return Status::InvalidArgument(out + " exists and is not a raw export: not replacing it");
    }
    fs::remove_all(old, ec);
    if (std::rename(out.c_str(), old.c_str()) != 0) {
      return Status::IOError("cannot move " + out + " aside: " + std::strerror(errno));
    }
  }
  if (std::rename(tmp.c_str(), out.c_str()) != 0) {
    return Status::IOError("cannot rename " + tmp + " to " + out + ": " + std::strerror(errno));
  }
  fs::remove_all(old, ec);
  return Status::Ok();
}

}  // namespace

Status write_raw_files(ExportJob& job, const std::string& dir, SharedNodes* shared) {
  const bool material = job.mesh.has_material();
  uint64_t dangling = 0, boundary = 0;
  WEAVER_RETURN_IF_ERROR(count_boundary(job, &boundary));
  WEAVER_RETURN_IF_ERROR(count_dangling(job, &dangling));
  const int64_t pairs = shared != nullptr ? int64_t(shared->count(job.sel.part)) : -1;
  GeoFrame geo;
  const bool georeferenced = job.georeferenced(&geo);
  const GeoTransform transform(geo);
  const std::vector<Array> arrays =
      layout(job.node_count(), job.element_count(), dangling,
             job.options.units == ExportUnits::kTicks, material, job.mesh.has_q(), !job.sel.whole(),
             pairs, georeferenced, job.mesh.has_solid(), boundary);
  OutputFile bin(dir + "/mesh.bin");
  WEAVER_RETURN_IF_ERROR(bin.open());
  std::vector<Section> out;
  for (const Array& a : arrays) out.emplace_back(bin, a.offset, job.section_buffer);
  WEAVER_RETURN_IF_ERROR(write_nodes(job, out, georeferenced ? &transform : nullptr));
  WEAVER_RETURN_IF_ERROR(write_elements(job, out, material, job.mesh.has_q()));
  if (shared != nullptr) WEAVER_RETURN_IF_ERROR(write_shared(job, *shared, out));
  if (boundary > 0) {
    WEAVER_RETURN_IF_ERROR(for_each_boundary(job, [&](const BoundaryRecord& r) {
      const int64_t f[3] = {int64_t(r.element), r.face, r.part};
      WEAVER_RETURN_IF_ERROR(out[kBoundaryFaces].put(f, sizeof f));
      return out[kBoundaryKind].value(r.kind);
    }));
  }
  for (Section& s : out) WEAVER_RETURN_IF_ERROR(s.flush());
  uint64_t bytes = 0;
  for (const Array& a : arrays) bytes = std::max(bytes, a.offset + a.bytes());
  job.result->bytes += bytes;
  WEAVER_RETURN_IF_ERROR(bin.finish());
  const std::string text = json(arrays, job, dangling);
  job.local.reset();  // its scratch files go before the directory is renamed
  job.result->bytes += text.size();
  return write_text_file(dir + "/mesh.json", text);
}

Status start_export_dir(const std::string& out, std::string* tmp) {
  *tmp = out + ".tmp";
  std::error_code ec;
  fs::remove_all(*tmp, ec);  // left by an interrupted export
  if (::mkdir(tmp->c_str(), 0755) != 0) {
    return Status::IOError("cannot create directory " + *tmp + ": " + std::strerror(errno));
  }
  return Status::Ok();
}

Status finish_export_dir(ExportJob& job, const std::string& tmp, const std::string& out,
                         Status written) {
  if (written.ok()) written = install_dir(tmp, out);
  if (!written.ok()) {
    job.local.reset();  // its scratch files first
    std::error_code ec;
    fs::remove_all(tmp, ec);
  }
  return written;
}

Status write_raw(ExportJob& job) {
  if (job.options.parts > 1) return write_raw_parts(job);
  std::string tmp;
  WEAVER_RETURN_IF_ERROR(start_export_dir(job.options.out, &tmp));
  Status st;
  if (job.options.has_box) {
    Selection s;
    st = job.box_selection(&s);
    if (st.ok()) st = job.select(s, true, tmp + "/scratch");
  }
  job.plan(job.node_count() + job.element_count());
  if (st.ok()) st = write_raw_files(job, tmp, nullptr);
  return finish_export_dir(job, tmp, job.options.out, st);
}

}  // namespace weaver
