#include "db/compact.h"

#include <map>
#include <memory>

#include "db/database.h"

namespace weaver {
namespace {

// Records moved a batch at a time: the append copies whole runs.
constexpr size_t kBatch = 4096;

// Appends every record of `from`, in key order, to `to`.
Status copy_records(BTree& from, BTree& to) {
  BTreeCursor c;
  WEAVER_RETURN_IF_ERROR(from.seek_cursor(0, &c));
  const uint32_t payload = from.payload_size();
  std::vector<uint64_t> keys;
  std::vector<std::byte> vals;
  keys.reserve(kBatch);
  vals.reserve(kBatch * payload);
  while (c.valid()) {
    keys.push_back(c.key());
    vals.insert(vals.end(), c.payload(), c.payload() + payload);
    WEAVER_RETURN_IF_ERROR(c.next());
    if (keys.size() == kBatch || !c.valid()) {
      WEAVER_RETURN_IF_ERROR(to.append_batch(keys.data(), vals.data(), keys.size()));
      keys.clear();
      vals.clear();
    }
  }
  return Status::Ok();
}

}  // namespace

Status compact_database(const std::string& db_dir, MemoryBudget memory, CompactResult* r) {
  *r = CompactResult{};
  MemoryPlan plan(memory);
  const uint64_t reader_pool = plan.take("shard readers", 1, 2, 64ull << 20);
  const uint64_t writer_pool = plan.take("joined table's writer", 1, 4, 16ull << 20);
  std::unique_ptr<Database> db;
  WEAVER_RETURN_IF_ERROR(Database::open(db_dir, Database::Mode::kWrite, false, &db));
  std::map<std::string, std::string> tables;  // every table after the commit
  std::vector<std::string> made;
  Status st;
  for (const std::string& name : db->table_names()) {
    const std::vector<ShardEntry> shards = db->shards_of(name);
    tables[name] = name;  // replaced below by its file
    if (shards.empty()) continue;
    std::unique_ptr<BTree> from, to;
    std::string file;
    st = db->open_table(name, reader_pool, &from);
    if (st.ok()) st = db->create_table(name, from->options(), writer_pool, &to, &file);
    if (!st.ok()) break;
    made.push_back(file);
    st = copy_records(*from, *to);
    if (st.ok()) st = to->commit();
    if (!st.ok()) break;
    tables[name] = file;
    r->tables.push_back({name, shards.size(), to->size(), to->file_bytes()});
  }
  if (st.ok() && !made.empty()) {
    // Every other table as it is: its value in the manifest, untouched.
    for (auto& [name, value] : tables) {
      if (value == name) value = db->table_value(name);
    }
    st = db->commit_exactly(tables);
  }
  if (!st.ok()) {
    for (const std::string& f : made) db->abandon(f);
  }
  return st;
}

}  // namespace weaver
