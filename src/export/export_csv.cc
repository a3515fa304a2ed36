#include "export/export_csv.h"

#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <memory>

#include "db/database.h"
#include "db/node_table.h"
#include "db/octant_table.h"
#include "schema/node.h"
#include "schema/octant.h"

namespace weaver {
namespace {

// A CSV file being written: buffered, completed by rename.
class CsvWriter {
 public:
  explicit CsvWriter(std::string path) : path_(std::move(path)), tmp_(path_ + ".tmp") {}
  ~CsvWriter() {
    if (f_ != nullptr) {
      std::fclose(f_);
      std::remove(tmp_.c_str());
    }
  }
  Status open(const char* header) {
    f_ = std::fopen(tmp_.c_str(), "wb");
    if (f_ == nullptr)
      return Status::IOError("cannot create " + tmp_ + ": " + std::strerror(errno));
    std::setvbuf(f_, nullptr, _IOFBF, 1 << 20);
    std::fputs(header, f_);
    return Status::Ok();
  }
  void field(uint64_t v) {
    char buf[24];
    const auto r = std::to_chars(buf, buf + sizeof buf, v);
    line_.append(buf, r.ptr);
  }
  void text(const char* s) { line_ += s; }
  void comma() { line_ += ','; }
  void end_line() {
    line_ += '\n';
    std::fwrite(line_.data(), 1, line_.size(), f_);
    line_.clear();
  }
  Status finish() {
    const bool ok = std::fflush(f_) == 0 && !std::ferror(f_);
    std::fclose(f_);
    f_ = nullptr;
    if (!ok || std::rename(tmp_.c_str(), path_.c_str()) != 0) {
      std::remove(tmp_.c_str());
      return Status::IOError("cannot write " + path_ + ": " + std::strerror(errno));
    }
    return Status::Ok();
  }

 private:
  std::string path_, tmp_;
  FILE* f_ = nullptr;
  std::string line_;
};

// The id of the node at c; Corruption if the node table lacks it.
Status node_id(BTree& nodes, Coord c, uint64_t* id) {
  bool present = false;
  WEAVER_RETURN_IF_ERROR(nodes.rank_exact(node_key(c), id, &present));
  if (!present) {
    return Status::Corruption("node (" + std::to_string(c.x) + " " + std::to_string(c.y) + " " +
                              std::to_string(c.z) +
                              ") is missing from the node table: run 'weaver extract' again");
  }
  return Status::Ok();
}

// Reports every 2^16 rows: `before` rows written by earlier files, of `total`.
struct RowProgress {
  const ProgressFn& fn;
  uint64_t before, total;
  void row(uint64_t id) const {
    if (fn && id % (1 << 16) == 0)
      fn(before + id, double(before + id) / std::max<uint64_t>(1, total));
  }
};

Status write_nodes(BTree& nodes, const std::string& path, const RowProgress& progress,
                   uint64_t* count) {
  CsvWriter out(path);
  WEAVER_RETURN_IF_ERROR(out.open("id,x,y,z,kind,a0,a1,a2,a3\n"));
  BTreeCursor c;
  WEAVER_RETURN_IF_ERROR(nodes.seek_cursor(0, &c));
  for (uint64_t id = 0; c.valid(); ++id) {
    progress.row(id);
    const Coord p = morton_decode(c.key());
    const uint8_t raw = static_cast<uint8_t>(c.payload()[0]);
    if (raw > 2)
      return Status::Corruption(nodes.file_name() + ": bad node kind " + std::to_string(raw));
    const NodeKind kind = static_cast<NodeKind>(raw);
    out.field(id), out.comma(), out.field(p.x), out.comma(), out.field(p.y), out.comma();
    out.field(p.z), out.comma(), out.text(node_kind_name(kind));
    Coord anchors[4];
    const int n = node_anchors(p, kind, anchors);
    for (int i = 0; i < 4; ++i) {
      out.comma();
      if (i >= n) continue;
      uint64_t aid = 0;
      WEAVER_RETURN_IF_ERROR(node_id(nodes, anchors[i], &aid));
      out.field(aid);
    }
    out.end_line();
    *count = id + 1;
    WEAVER_RETURN_IF_ERROR(c.next());
  }
  return out.finish();
}

Status write_elements(BTree& octants, BTree& nodes, const std::string& path,
                      const RowProgress& progress, uint64_t* count) {
  CsvWriter out(path);
  WEAVER_RETURN_IF_ERROR(out.open("id,x,y,z,level,n0,n1,n2,n3,n4,n5,n6,n7\n"));
  BTreeCursor c;
  WEAVER_RETURN_IF_ERROR(octants.seek_cursor(0, &c));
  for (uint64_t id = 0; c.valid(); ++id) {
    progress.row(id);
    const Octant o = octant_from_key(c.key());
    out.field(id), out.comma(), out.field(o.x), out.comma(), out.field(o.y), out.comma();
    out.field(o.z), out.comma(), out.field(o.level);
    for (int k = 0; k < 8; ++k) {
      uint64_t nid = 0;
      WEAVER_RETURN_IF_ERROR(node_id(nodes, octant_corner(o, k), &nid));
      out.comma(), out.field(nid);
    }
    out.end_line();
    *count = id + 1;
    WEAVER_RETURN_IF_ERROR(c.next());
  }
  return out.finish();
}

}  // namespace

ExportMemory::ExportMemory(MemoryBudget budget) : plan(budget) {
  // Every element looks up its 8 corners and every dangling node its
  // anchors: the larger the node pool, the fewer of those go to disk.
  node_pool = plan.take("node table pool", 1, 2);
  // The leaves are read once, in order.
  octant_pool = plan.take("octant table pool", 1, 8, 4ull << 20);
}

Status export_csv(const std::string& db_dir, const ExportOptions& options, ExportResult* result) {
  *result = ExportResult{};
  std::unique_ptr<Database> db;
  WEAVER_RETURN_IF_ERROR(Database::open(db_dir, Database::Mode::kRead, false, &db));
  if (!db->has_table(kNodeTable)) {
    return Status::NotFound(db_dir + ": no mesh yet (run 'weaver extract' first)");
  }
  std::unique_ptr<BTree> nodes, octants;
  const ExportMemory memory(options.memory);
  WEAVER_RETURN_IF_ERROR(db->open_table(kNodeTable, memory.node_pool, &nodes));
  WEAVER_RETURN_IF_ERROR(db->open_table(kOctantTable, memory.octant_pool, &octants));
  const uint64_t node_rows = options.nodes_path.empty() ? 0 : nodes->size();
  const uint64_t total = node_rows + (options.elements_path.empty() ? 0 : octants->size());
  if (!options.nodes_path.empty()) {
    WEAVER_RETURN_IF_ERROR(write_nodes(*nodes, options.nodes_path,
                                       RowProgress{options.progress, 0, total}, &result->nodes));
  }
  if (!options.elements_path.empty()) {
    WEAVER_RETURN_IF_ERROR(write_elements(*octants, *nodes, options.elements_path,
                                          RowProgress{options.progress, node_rows, total},
                                          &result->elements));
  }
  return Status::Ok();
}

}  // namespace weaver
