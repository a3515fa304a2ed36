#include "import/import.h"

#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <memory>

#include "db/database.h"
#include "import/octant_text.h"
#include "sort/key_tag.h"
#include "storage/lsm.h"

namespace weaver {

ImportMemory::ImportMemory(MemoryBudget budget) : plan(budget) {
  // A sorted append touches only the right spine of a table: a small pool
  // each for the table of the octants in order and for the merged one.
  table_pool = plan.take("table pools (2 tables)", 1, 4, 16ull << 20) / 2;
  // The LSM's runs are only read by cursors, in order: a small pool each, and
  // at most 3 runs per tier (5 tiers cover 4^5 memtables).
  run_pool = plan.take("LSM run pools (16 runs)", 1, 8, kMaxRuns * (256ull << 10)) / kMaxRuns;
  // The 1 MiB text read chunk and allocator slack.
  plan.take("text chunk and slack", 1, 8, 4ull << 20);
  // The larger the memtable, the fewer runs to merge.
  memtable = plan.take_rest("LSM memtable");
}

namespace {

constexpr uint64_t kProgressEvery = 1 << 20;

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
    return Status::InvalidArgument(at + "octant " + describe_octant(later_is_b ? b : a) +
                                   " overlaps octant " + describe_octant(later_is_b ? a : b) +
                                   other);
  }
  return Status::Ok();
}

// The first line of `path` holding octant `key` (0 if none): error messages
// only, for octants that went in without their line.
uint64_t line_of(const std::string& path, uint64_t key) {
  uint64_t found = 0;
  read_octant_text(path, [&](const Octant& o, uint64_t line) {
    if (octant_key(o) != key) return Status::Ok();
    found = line;
    return Status::Busy("found");  // stops the read
  });
  return found;
}

// check_neighbours, after finding the lines of octants that came without one
// (tag 0), when there is something to report.
Status check_pair(const std::string& path, KeyTag prev, KeyTag cur) {
  if (check_neighbours(path, prev, cur).ok()) return Status::Ok();
  if (prev.tag == 0) prev.tag = line_of(path, prev.key);
  if (cur.tag == 0) cur.tag = line_of(path, cur.key);
  return check_neighbours(path, prev, cur);
}

// The octant table being built: sorted append, the overlap check against the
// previous octant, and the level counts.
class TableBuilder {
 public:
  TableBuilder(const std::string& path, BTree& table) : path_(path), table_(table) {}
  Status add(const KeyTag& cur) {
    if (has_prev_) WEAVER_RETURN_IF_ERROR(check_pair(path_, prev_, cur));
    WEAVER_RETURN_IF_ERROR(table_.append(cur.key, nullptr));
    ++levels_[octant_from_key(cur.key).level];
    prev_ = cur;
    has_prev_ = true;
    return Status::Ok();
  }
  // Whether cur can go straight on (it sorts after the previous octant).
  bool in_order(uint64_t key) const { return !has_prev_ || key > prev_.key; }
  const LevelCounts& levels() const { return levels_; }

 private:
  const std::string& path_;
  BTree& table_;
  KeyTag prev_{};
  bool has_prev_ = false;
  LevelCounts levels_{};
};

// Octants that arrive out of order go to an LSM store keyed by octant, with
// the line as payload; a repeated octant is reported when the LSM finds it.
Status make_lsm(const std::string& dir, const std::string& path, const ImportMemory& memory,
                bool packed, std::unique_ptr<LsmTree>* out) {
  LsmOptions o;
  std::string error;
  o.table.schema = *RecordSchema::parse("line:u64", &error);
  o.table.packed = packed;
  o.memtable_bytes = memory.memtable;
  o.run_pool_bytes = memory.run_pool;
  o.on_shadow = [path](uint64_t key, const std::byte* newer, const std::byte* older) {
    KeyTag a{key, 0}, b{key, 0};
    std::memcpy(&a.tag, older, 8);
    std::memcpy(&b.tag, newer, 8);
    return check_pair(path, a, b);
  };
  return LsmTree::create(dir, o, out);
}

// Sorted input goes straight into the table.  From the first octant out of
// order on, the rest goes to the LSM, and at the end the table so far and
// the LSM are merged into a second table.
Status read_input(const std::string& text_path, const ImportOptions& options,
                  const ImportMemory& memory, const std::string& scratch, TableBuilder& direct,
                  std::unique_ptr<LsmTree>* lsm) {
  uint64_t count = 0;
  return read_octant_text(text_path, [&](const Octant& o, uint64_t line) -> Status {
    if (options.progress && ++count % kProgressEvery == 0) options.progress(count, -1);
    const uint64_t key = octant_key(o);
    if (*lsm == nullptr && direct.in_order(key)) return direct.add({key, line});
    if (*lsm == nullptr)
      WEAVER_RETURN_IF_ERROR(make_lsm(scratch, text_path, memory, options.packed, lsm));
    return (*lsm)->put(key, reinterpret_cast<const std::byte*>(&line), nullptr);
  });
}

// The octants appended in order (tags unknown: 0) merged with the LSM's.
Status merge_into(BTree& sorted, LsmTree& lsm, TableBuilder& out) {
  BTreeCursor a;
  std::unique_ptr<Cursor> b;
  WEAVER_RETURN_IF_ERROR(sorted.seek_cursor(0, &a));
  WEAVER_RETURN_IF_ERROR(lsm.seek(0, &b));
  while (a.valid() || b->valid()) {
    KeyTag next{};
    if (b->valid() && (!a.valid() || b->key() <= a.key())) {
      next.key = b->key();
      std::memcpy(&next.tag, b->payload(), 8);
      WEAVER_RETURN_IF_ERROR(b->next());
    } else {
      next.key = a.key();
      WEAVER_RETURN_IF_ERROR(a.next());
    }
    WEAVER_RETURN_IF_ERROR(out.add(next));
  }
  return Status::Ok();
}

Status finish_table(BTree& table, const TableBuilder& built, const std::string& text_path,
                    const ImportOptions& options, ImportResult* result) {
  if (table.size() == 0) return Status::InvalidArgument(text_path + ": no octants in the file");
  table.set_metadata(units_to_metadata(options.units) + levels_to_metadata(built.levels()));
  WEAVER_RETURN_IF_ERROR(table.commit());
  result->octants = table.size();
  result->table_bytes = table.file_bytes();
  return Status::Ok();
}

// Builds the table into *file_name (committed to its file, not yet live).
Status build_table(Database& db, const std::string& text_path, const ImportOptions& options,
                   const std::string& scratch, std::string* file_name, ImportResult* result) {
  TableOptions topt;
  topt.key_kind = KeyKind::kOctant;
  topt.packed = options.packed;
  const ImportMemory memory(options.memory);
  const uint64_t pool = memory.table_pool;
  std::unique_ptr<BTree> table;
  WEAVER_RETURN_IF_ERROR(db.create_table(kOctantTable, topt, pool, &table, file_name));
  TableBuilder direct(text_path, *table);
  std::unique_ptr<LsmTree> lsm;
  WEAVER_RETURN_IF_ERROR(read_input(text_path, options, memory, scratch, direct, &lsm));
  if (lsm == nullptr) return finish_table(*table, direct, text_path, options, result);
  result->runs_spilled = lsm->runs_written();
  std::unique_ptr<BTree> merged;
  std::string merged_name;
  WEAVER_RETURN_IF_ERROR(db.create_table(kOctantTable, topt, pool, &merged, &merged_name));
  TableBuilder out(text_path, *merged);
  Status st = merge_into(*table, *lsm, out);
  if (st.ok()) st = finish_table(*merged, out, text_path, options, result);
  table.reset();
  db.abandon(*file_name);
  *file_name = merged_name;
  if (!st.ok()) db.abandon(merged_name), file_name->clear();
  return st;
}

Status check_input_file(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    return Status::InvalidArgument(path + ": is a directory");
  if (!std::filesystem::exists(path, ec)) return Status::NotFound(path + ": no such file");
  return Status::Ok();
}

// The units of the table being replaced, for those the options do not give.
Status keep_units(const Database& db, ImportOptions* o) {
  if (!db.has_table(kOctantTable) || (o->tick_given && o->origin_given)) return Status::Ok();
  std::unique_ptr<BTree> old;
  WEAVER_RETURN_IF_ERROR(db.open_table(kOctantTable, 64 << 10, &old));
  Units kept;
  units_from_metadata(old->options().metadata, &kept);
  if (!o->tick_given) o->units.tick_m = kept.tick_m;
  if (!o->origin_given) o->units.origin_m = kept.origin_m;
  return Status::Ok();
}

}  // namespace

Status import_octants(const std::string& db_dir, const std::string& text_path,
                      const ImportOptions& options, ImportResult* result) {
  WEAVER_RETURN_IF_ERROR(check_input_file(text_path));
  const bool existed = std::filesystem::exists(db_dir);
  std::unique_ptr<Database> db;
  WEAVER_RETURN_IF_ERROR(Database::open(db_dir, Database::Mode::kWrite, true, &db));
  ImportOptions o = options;
  WEAVER_RETURN_IF_ERROR(keep_units(*db, &o));
  const std::string scratch = db_dir + "/tmp-import-" + std::to_string(::getpid());
  std::string file_name;
  Status st = build_table(*db, text_path, o, scratch, &file_name, result);
  std::error_code ec;
  std::filesystem::remove_all(scratch, ec);
  if (st.ok()) st = db->commit({{kOctantTable, file_name}});
  if (!st.ok()) {
    if (!file_name.empty()) db->abandon(file_name);
    db.reset();
    // A database this import created is removed again: "left as it was".
    if (!existed) std::filesystem::remove_all(db_dir, ec);
  }
  return st;
}

}  // namespace weaver
