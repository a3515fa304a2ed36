#include "import/import.h"

#include <unistd.h>

#include <filesystem>
#include <memory>

#include "db/database.h"
#include "sort/external_sort.h"
#include "import/octant_text.h"

namespace weaver {
namespace {

constexpr uint64_t kProgressEvery = 1 << 20;
// Memory outside the sorter and the pool: the 1 MiB text read chunk, code
// and allocator slack.
constexpr uint64_t kFixedOverhead = 4ull << 20;

// The B+tree pool for the sorted append: it needs only the right spine, so a
// small pool suffices; the sorter gets the rest of the budget.
uint64_t append_pool_bytes(uint64_t budget) { return std::min<uint64_t>(budget / 8, 8ull << 20); }
uint64_t sorter_bytes(uint64_t budget) {
  const uint64_t reserved = append_pool_bytes(budget) + kFixedOverhead;
  return budget > 2 * reserved ? budget - reserved : budget / 2;
}

std::string describe(const Octant& o) {
  return "(" + std::to_string(o.x) + " " + std::to_string(o.y) + " " + std::to_string(o.z) + " " +
         std::to_string(o.level) + ")";
}

// In key order (preorder) two octants overlap iff they are equal or one is
// the other's ancestor, and every key between an ancestor and its descendant
// lies in the ancestor's subtree: if any pair overlaps, an adjacent pair does.
Status check_neighbours(const std::string& path, const KeyTag& prev, const KeyTag& cur) {
  const Octant a = octant_from_key(prev.key), b = octant_from_key(cur.key);
  const std::string at = path + ":" + std::to_string(std::max(prev.tag, cur.tag)) + ": ";
  const std::string other = " at line " + std::to_string(std::min(prev.tag, cur.tag));
  if (prev.key == cur.key) return Status::InvalidArgument(at + "duplicate of the octant" + other);
  if (octant_is_ancestor(a, b)) {
    const bool later_is_b = cur.tag > prev.tag;
    return Status::InvalidArgument(at + "octant " + describe(later_is_b ? b : a) +
                                   " overlaps octant " + describe(later_is_b ? a : b) + other);
  }
  return Status::Ok();
}

Status sort_input(const std::string& text_path, const ImportOptions& options,
                  ExternalSorter* sorter, uint64_t* count) {
  *count = 0;
  WEAVER_RETURN_IF_ERROR(read_octant_text(text_path, [&](const Octant& o, uint64_t line) {
    if (options.progress && ++*count % kProgressEvery == 0) options.progress("read", *count);
    return sorter->add({octant_key(o), line});
  }));
  return sorter->finish();
}

Status build_table(Database& db, const std::string& text_path, const ImportOptions& options,
                   ExternalSorter& sorter, std::string* file_name, ImportResult* result) {
  TableOptions topt;
  topt.key_kind = KeyKind::kOctant;
  std::unique_ptr<BTree> table;
  WEAVER_RETURN_IF_ERROR(db.create_table(kOctantTable, topt,
                                         append_pool_bytes(options.memory_bytes), &table,
                                         file_name));
  KeyTag prev{}, cur{};
  bool done = false, first = true;
  LevelCounts levels{};
  while (true) {
    WEAVER_RETURN_IF_ERROR(sorter.next(&cur, &done));
    if (done) break;
    if (!first) WEAVER_RETURN_IF_ERROR(check_neighbours(text_path, prev, cur));
    WEAVER_RETURN_IF_ERROR(table->append(cur.key, nullptr));
    ++levels[octant_from_key(cur.key).level];
    if (options.progress && table->size() % kProgressEvery == 0) {
      options.progress("write", table->size());
    }
    prev = cur;
    first = false;
  }
  if (table->size() == 0) return Status::InvalidArgument(text_path + ": no octants in the file");
  table->set_metadata(units_to_metadata(options.units) + levels_to_metadata(levels));
  WEAVER_RETURN_IF_ERROR(table->commit());
  result->octants = table->size();
  result->table_bytes = table->file_bytes();
  return Status::Ok();
}

}  // namespace

Status import_octants(const std::string& db_dir, const std::string& text_path,
                      const ImportOptions& options, ImportResult* result) {
  if (!std::filesystem::is_regular_file(text_path)) {
    return Status::NotFound(text_path + ": no such file");
  }
  const bool existed = std::filesystem::exists(db_dir);
  std::unique_ptr<Database> db;
  WEAVER_RETURN_IF_ERROR(Database::open(db_dir, Database::Mode::kWrite, true, &db));
  const std::string scratch = db_dir + "/tmp-import-" + std::to_string(::getpid());
  std::string file_name;
  Status st;
  {
    ExternalSorter sorter(scratch, sorter_bytes(options.memory_bytes));
    uint64_t count = 0;
    st = sort_input(text_path, options, &sorter, &count);
    if (st.ok()) st = build_table(*db, text_path, options, sorter, &file_name, result);
    result->runs_spilled = sorter.runs_spilled();
  }
  if (st.ok()) st = db->commit({{kOctantTable, file_name}});
  if (!st.ok()) {
    if (!file_name.empty()) db->abandon(file_name);
    db.reset();
    // A database this import created is removed again: "left as it was".
    std::error_code ec;
    if (!existed) std::filesystem::remove_all(db_dir, ec);
  }
  return st;
}

}  // namespace weaver
