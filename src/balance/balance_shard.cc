#include "balance/balance_shard.h"

#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "balance/window_balance.h"
#include "db/table_files.h"
#include "model/velocity_model.h"
#include "schema/octant.h"
#include "util/octant_key_stream.h"

namespace weaver {
namespace {

// Where each rank's part begins (cut_equal_runs): key[s] its first leaf's
// key, lo[s] the Morton code its part of the space begins at.
struct Cut {
  std::vector<uint64_t> key, lo;
  // The rank whose part of the space holds Morton code m.
  size_t owner(uint64_t m) const { return rank_holding(lo, m); }
};

uint64_t span_of(int level) { return uint64_t{1} << (3 * (kMaxLevel - level)); }

// Whether o's insulation layer lies in the Morton range [lo, hi): the
// smallest aligned octant holding the layer's bounding box does.
bool layer_inside(const Octant& o, uint64_t lo, uint64_t hi) {
  const uint32_t s = octant_edge(o);
  const uint32_t c[3] = {o.x, o.y, o.z};
  uint32_t low[3], diff = 0;
  for (int a = 0; a < 3; ++a) {
    low[a] = c[a] >= s ? c[a] - s : 0;
    const uint32_t high = std::min<uint32_t>(c[a] + 2 * s, kRootEdge) - 1;
    diff |= low[a] ^ high;
  }
  const int bits = diff == 0 ? 0 : 32 - std::countl_zero(diff);  // the holder's edge is 2^bits
  const uint64_t m = morton_encode(low[0], low[1], low[2]) >> (3 * bits) << (3 * bits);
  return m >= lo && m + (uint64_t{1} << (3 * bits)) <= hi;
}

// octant_key_neighbour for any level (it takes levels below the finest).
bool neighbour_key(uint64_t key, Direction d, uint64_t* out) {
  Octant n;
  if (!octant_neighbour(octant_from_key(key), d, &n)) return false;
  *out = octant_key(n);
  return true;
}

// Round 1: for each other rank, the octants of this rank's leaves'
// insulation layers that reach into its part of the space, sorted, once each.
Status insulation_queries(BTree& t, const Cut& cut, int rank,
                          std::vector<std::vector<uint64_t>>* queries) {
  queries->assign(cut.key.size() - 1, {});
  const uint64_t lo = cut.lo[rank], hi = cut.lo[rank + 1];
  BTreeCursor c;
  WEAVER_RETURN_IF_ERROR(t.seek_keys(cut.key[rank], &c));
  while (c.valid() && c.key() < cut.key[rank + 1]) {
    const uint64_t key = c.key();
    const int level = octant_key_level(key);
    const uint64_t span = span_of(level);
    if (layer_inside(octant_from_key(key), lo, hi)) {  // most leaves: nothing to ask
      WEAVER_RETURN_IF_ERROR(c.next());
      continue;
    }
    for (const Direction d : kAllDirections) {
      uint64_t n = 0;
      if (level < kMaxLevel ? !octant_key_neighbour(key, d, &n) : !neighbour_key(key, d, &n)) {
        continue;
      }
      const uint64_t a = octant_key_morton(n);
      if (a >= lo && a + span <= hi) continue;  // inside this rank's part
      for (size_t s = cut.owner(a); s <= cut.owner(a + span - 1); ++s) {
        if (s != size_t(rank)) (*queries)[s].push_back(n);
      }
    }
    WEAVER_RETURN_IF_ERROR(c.next());
  }
  for (auto& q : *queries) {
    std::sort(q.begin(), q.end());
    q.erase(std::unique(q.begin(), q.end()), q.end());
  }
  return Status::Ok();
}

// Round 2: this rank's leaves that meet the queried octants (the leaf
// holding one, or the leaves inside it): their keys alone (a layer leaf
// only shapes the balance; its material never reaches the rank's output).  The
// queries come sorted, so one cursor goes forward through them, and a cell
// inside one answered already (the layers of neighbouring leaves overlap)
// or held by a leaf sent already adds nothing.
class Answerer {
 public:
  Answerer(BTree& t, uint64_t first, uint64_t next) : t_(t), first_(first), next_(next) {}

  Status answer(uint64_t q, std::vector<uint64_t>* out) {
    const uint64_t begin = octant_key_morton(q), end = begin + span_of(octant_key_level(q));
    if (begin >= done_begin_ && end <= done_end_) return Status::Ok();  // inside the last cell
    if (!(begin >= held_begin_ && begin < held_end_)) {
      uint64_t key = 0;
      bool found = false;
      WEAVER_RETURN_IF_ERROR(floor_holding(t_, octant_from_key(q), &key, nullptr, &found));
      if (found && key != q) {
        held_begin_ = octant_key_morton(key);
        held_end_ = held_begin_ + span_of(octant_key_level(key));
        if (key >= first_ && key < next_) out->push_back(key);
      }
    }
    const uint64_t target = std::max(q, first_);
    uint64_t last = 0;
    if (!c_.valid() || (c_.key() < target && !c_.skip_in_leaf(target - 1, &last))) {
      WEAVER_RETURN_IF_ERROR(t_.seek_keys(target, &c_));
    }
    while (c_.valid() && c_.key() < next_ && octant_key_morton(c_.key()) < end) {
      out->push_back(c_.key());
      WEAVER_RETURN_IF_ERROR(c_.next());
    }
    done_begin_ = begin, done_end_ = end;
    return Status::Ok();
  }

 private:
  BTree& t_;
  const uint64_t first_, next_;
  BTreeCursor c_;
  uint64_t done_begin_ = 1, done_end_ = 0;  // the last cell answered (Morton range)
  uint64_t held_begin_ = 1, held_end_ = 0;  // the last leaf found holding a cell
};

// The leaves that arrived, as (key, payload) records sorted by key.
struct Layer {
  std::vector<uint64_t> keys;
  std::vector<std::byte> payloads;
};

// The layer's leaves, from every rank's sorted keys
// (util/octant_key_stream.h), with zero payloads.
Status decode_layer(const std::vector<std::string>& received, uint32_t payload, Layer* l) {
  for (const std::string& b : received) {
    if (!decode_octant_keys(b, &l->keys)) return Status::Corruption("a layer cut short");
  }
  std::sort(l->keys.begin(), l->keys.end());
  l->keys.erase(std::unique(l->keys.begin(), l->keys.end()), l->keys.end());
  l->payloads.assign(l->keys.size() * payload, std::byte{0});
  return Status::Ok();
}

// The scratch database: this rank's leaves and the layer, in key order.
Status write_scratch(BTree& t, const Cut& cut, int rank, const Layer& layer,
                     const std::string& scratch) {
  std::unique_ptr<Database> db;
  WEAVER_RETURN_IF_ERROR(Database::open(scratch, Database::Mode::kWrite, true, &db));
  std::unique_ptr<BTree> out;
  std::string file;
  TableOptions plain = t.options();
  plain.packed = false;  // see BalanceOptions::output_packed
  WEAVER_RETURN_IF_ERROR(db->create_table(kOctantTable, plain, 4 << 20, &out, &file));
  const uint32_t payload = t.payload_size();
  LevelCounts levels{};
  BTreeCursor c;
  Status st = t.seek_cursor(cut.key[rank], &c);
  size_t i = 0;
  auto mine = [&] { return c.valid() && c.key() < cut.key[rank + 1]; };
  while (st.ok() && (mine() || i < layer.keys.size())) {
    if (mine() && (i == layer.keys.size() || c.key() < layer.keys[i])) {
      ++levels[octant_key_level(c.key())];
      st = out->append(c.key(), c.payload());
      if (st.ok()) st = c.next();
    } else {
      ++levels[octant_key_level(layer.keys[i])];
      st = out->append(layer.keys[i], layer.payloads.data() + size_t{payload} * i);
      ++i;
    }
  }
  // The balance keeps the items it does not count, so its output (this
  // rank's shard) carries the place.
  if (st.ok()) {
    out->set_metadata(with_shard_place(with_levels(t.options().metadata, levels),
                                       shard_place_among(cut.key, rank)));
  }
  return db->publish(kOctantTable, file, out, st);
}

// The balanced scratch table, which holds this rank's leaves alone
// (BalanceOptions::keep_from/keep_to), becomes its shard: renamed into
// db_dir, then described for the manifest.
Status adopt_shard(const std::string& db_dir, const std::string& scratch, const std::string& file,
                   BalanceShardResult* r, ShardEntry* entry) {
  std::string from;
  {
    std::unique_ptr<Database> db;
    WEAVER_RETURN_IF_ERROR(Database::open(scratch, Database::Mode::kRead, false, &db));
    from = db->table_path(kOctantTable);
  }
  const std::string to = db_dir + "/" + file;
  if (std::rename(from.c_str(), to.c_str()) != 0) {
    return Status::IOError("cannot rename " + from + " to " + to + ": " + std::strerror(errno));
  }
  std::unique_ptr<File> f;
  WEAVER_RETURN_IF_ERROR(open_posix_file(to, OpenMode::kReadOnly, &f));
  std::unique_ptr<BTree> t;
  WEAVER_RETURN_IF_ERROR(BTree::open(std::move(f), 1 << 20, &t));
  levels_from_metadata(t->options().metadata, &r->balance.levels);
  r->balance.output_leaves = t->size();
  r->table_bytes = t->file_bytes();
  entry->records = t->size();
  WEAVER_RETURN_IF_ERROR(t->select(0, &entry->first_key, nullptr));
  return t->select(t->size() - 1, &entry->last_key, nullptr);
}

// The windows' way: this rank's leaves balanced window by window against
// layers read from the table itself, which every rank sees: no exchange,
// no scratch copy.  *fitted false if a window outgrew the memory (nothing
// is kept then).
Status shard_by_windows(Database& db, BTree& t, const Cut& cut, const BalanceOptions& o, int rank,
                        const std::string& file, BalanceShardResult* r, ShardEntry* entry,
                        bool* fitted) {
  *fitted = true;
  const BalanceMemory memory(o.memory);
  std::vector<std::unique_ptr<BTree>> more;
  WindowOptions wo;
  WEAVER_RETURN_IF_ERROR(window_options(db, t, o, memory, &more, &wo));
  wo.first_leaf = t.size();
  wo.end_leaf = t.size();
  if (cut.key[rank] != UINT64_MAX) WEAVER_RETURN_IF_ERROR(t.rank(cut.key[rank], &wo.first_leaf));
  if (cut.key[rank + 1] != UINT64_MAX) {
    WEAVER_RETURN_IF_ERROR(t.rank(cut.key[rank + 1], &wo.end_leaf));
  }
  std::unique_ptr<VelocityModel> model;
  FillPayload fill;
  std::vector<std::string> model_dirs = o.model_dirs;
  model_dirs.push_back(db.dir());
  WEAVER_RETURN_IF_ERROR(model_material_fill(t.options(), model_dirs, memory.model, memory.surface,
                                             o.threads, &model, &fill));
  std::unique_ptr<BTree> out;
  WEAVER_RETURN_IF_ERROR(create_shard_table(db.dir(), file, t.options(), memory.output_pool, &out));
  Status st = balance_in_windows(wo, fill, *out, &r->balance, fitted);
  if (st.ok() && !*fitted) st = Status::Internal("a window outgrew the memory");
  if (st.ok()) out->set_metadata(with_levels(t.options().metadata, r->balance.levels));
  const Status done =
      finish_shard(db.dir(), out, st, shard_place_among(cut.key, rank), entry, &r->table_bytes);
  return *fitted ? done : Status::Ok();
}

// Whether every rank's windows fitted (one all-to-all of a byte).
Status all_fitted(const RankExchange& exchange, int ranks, bool mine, bool* all) {
  std::vector<std::string> received;
  WEAVER_RETURN_IF_ERROR(exchange(std::vector<std::string>(ranks, mine ? "1" : "0"), &received));
  *all =
      std::all_of(received.begin(), received.end(), [](const std::string& b) { return b == "1"; });
  return Status::Ok();
}

}  // namespace

Status balance_shard(const std::string& db_dir, const BalanceOptions& options, int rank, int ranks,
                     const std::string& file, const RankExchange& exchange, BalanceShardResult* r,
                     ShardEntry* entry) {
  *r = BalanceShardResult{};
  *entry = ShardEntry{file};
  std::unique_ptr<Database> db;
  std::unique_ptr<BTree> t;
  Cut cut;
  std::vector<std::vector<uint64_t>> queries;
  // Up to the exchanges, an error still takes part in them (sending nothing).
  Status st = Database::open(db_dir, Database::Mode::kRead, false, &db);
  if (st.ok() && !options.staged_octants.empty()) {
    st = db->stage_shards(kOctantTable, options.staged_octants);
  }
  if (st.ok()) st = db->open_table(kOctantTable, 16 << 20, &t);
  if (st.ok()) st = cut_equal_runs(*t, ranks, &cut.key, &cut.lo);
  if (options.algorithm != BalanceOptions::Algorithm::kClosure) {
    bool fitted = false, all = false;
    if (st.ok()) st = shard_by_windows(*db, *t, cut, options, rank, file, r, entry, &fitted);
    // Every rank takes part in the exchange, whatever happened to it; if
    // one failed or did not fit, all go the way of the exchanges (where an
    // error takes part too, and is returned at the end).
    WEAVER_RETURN_IF_ERROR(all_fitted(exchange, ranks, st.ok() && fitted, &all));
    r->bytes_sent += ranks - 1;  // a byte to each other rank, and from each
    r->bytes_received += ranks - 1;
    if (all) return Status::Ok();
    if (st.ok() && entry->records > 0) std::remove((db_dir + "/" + file).c_str());
    *r = BalanceShardResult{};
    *entry = ShardEntry{file};
  }
  if (st.ok()) st = insulation_queries(*t, cut, rank, &queries);
  std::vector<std::string> blobs(ranks), received;
  for (int s = 0; st.ok() && s < ranks; ++s) {
    blobs[s] = encode_octant_keys(queries[s]);
    r->queries_sent += queries[s].size();
  }
  for (const std::string& b : blobs) r->bytes_sent += b.size();
  Status ex = exchange(blobs, &received);
  for (const std::string& b : received) r->bytes_received += b.size();
  for (int s = 0; s < ranks; ++s) {
    blobs[s].clear();
    const std::string& qs = st.ok() && ex.ok() ? received[s] : std::string();
    if (qs.empty()) continue;
    Answerer answers(*t, cut.key[rank], cut.key[rank + 1]);
    std::vector<uint64_t> keys;
    size_t pos = 0;
    uint64_t q = 0, last = 0;
    while (st.ok() && pos < qs.size()) {
      if (!read_octant_key(qs, &pos, &last, &q)) st = Status::Corruption("a query cut short");
      if (st.ok()) st = answers.answer(q, &keys);
    }
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    blobs[s] = encode_octant_keys(keys);
  }
  for (const std::string& b : blobs) r->bytes_sent += b.size();
  const Status ex2 = exchange(st.ok() ? blobs : std::vector<std::string>(ranks), &received);
  WEAVER_RETURN_IF_ERROR(st);
  WEAVER_RETURN_IF_ERROR(ex);
  WEAVER_RETURN_IF_ERROR(ex2);
  for (const std::string& b : received) r->bytes_received += b.size();
  if (cut.key[rank] == cut.key[rank + 1]) return Status::Ok();  // no leaves: no shard
  Layer layer;
  WEAVER_RETURN_IF_ERROR(decode_layer(received, t->payload_size(), &layer));
  received = {}, blobs = {}, queries = {};  // the scratch balance gets the memory back
  r->layer_received = layer.keys.size();
  const std::string scratch =
      db_dir + "/tmp-balance-" + std::to_string(::getpid()) + "-" + std::to_string(rank);
  st = write_scratch(*t, cut, rank, layer, scratch);
  layer = Layer{};
  BalanceOptions own = options;
  // What the exchanges held is freed, but not always given back to the
  // system: the balance takes 3/4 of the budget (at 2 Hz on 4 ranks the
  // layer and its messages were 110 MB a rank).
  own.memory = MemoryBudget(std::max(MemoryBudget::kMinBytes, options.memory.bytes() / 4 * 3));
  own.keep_from = cut.key[rank];
  own.keep_to = cut.key[rank + 1];
  own.output_packed = t->options().packed ? 1 : 0;
  own.model_dirs.push_back(db_dir);  // the scratch database has no model table
  BalanceResult scratch_result;
  if (st.ok()) st = balance_octree(scratch, own, &scratch_result);
  if (st.ok()) st = adopt_shard(db_dir, scratch, file, r, entry);
  std::error_code ec;
  std::filesystem::remove_all(scratch, ec);
  return st;
}

}  // namespace weaver
