#include "balance/balance.h"

#include <unistd.h>

#include <array>
#include <algorithm>
#include <cstring>
#include <filesystem>
#include <functional>
#include <memory>
#include <vector>

#include "db/database.h"
#include "sort/external_sort.h"
#include "sort/sorted_spool.h"
#include "util/key_set.h"
#include "model/velocity_model.h"
#include "schema/octant.h"

namespace weaver {
namespace {

constexpr size_t kBatch = 4096;

// The 18 face and edge neighbour directions.
std::vector<std::array<int, 3>> face_edge_directions() {
  std::vector<std::array<int, 3>> dirs;
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const int nonzero = (dx != 0) + (dy != 0) + (dz != 0);
        if (nonzero == 1 || nonzero == 2) dirs.push_back({dx, dy, dz});
      }
  return dirs;
}

// Walks the octant table alongside a nondecreasing stream of keys and tells
// whether each octant overlaps the domain (the union of the leaves).
class DomainProbe {
 public:
  Status open(BTree& leaves) { return leaves.seek_cursor(0, &cursor_); }
  Status overlaps(uint64_t key, bool* yes) {
    while (cursor_.valid() && cursor_.key() <= key) {
      last_ = cursor_.key();
      has_last_ = true;
      WEAVER_RETURN_IF_ERROR(cursor_.next());
    }
    // A leaf equal to or containing the octant, or a leaf inside it.
    *yes = (has_last_ && key < octant_key_subtree_end(last_)) ||
           (cursor_.valid() && cursor_.key() < octant_key_subtree_end(key));
    return Status::Ok();
  }

 private:
  BTreeCursor cursor_;
  uint64_t last_ = 0;
  bool has_last_ = false;
};

// Reads a sorted source, skipping repeated keys.
Status next_unique(KeyTagSource& s, uint64_t* prev, bool* has_prev, KeyTag* out, bool* done) {
  while (true) {
    WEAVER_RETURN_IF_ERROR(s.next(out, done));
    if (*done) return Status::Ok();
    if (!*has_prev || out->key != *prev) {
      *prev = out->key;
      *has_prev = true;
      return Status::Ok();
    }
  }
}

// Where the budget goes (M = memory_bytes): the leaf table's pool takes up to
// M/8, the chunk of parents with its key set M/4, the candidate sorter M/4,
// and the spools (three per level) their buffers of M/512 each.  Everything
// else is sorted already: a level's parents arrive as two sorted streams (of
// the leaves, of the octants required one level finer), and each level's
// required octants come out of the candidate sorter in order.
class Balancer {
 public:
  Balancer(BTree& leaves, const BalanceOptions& o, const std::string& scratch, BalanceResult* r)
      : leaves_(leaves), o_(o), scratch_(scratch), r_(r), dirs_(face_edge_directions()) {}

  // Builds the required octants (into required_), level by level.
  // Without propagation (check_only) only the leaves' own requirements are
  // made: enough to tell whether the octree is balanced.
  Status closure(int max_level, bool propagate) {
    for (int l = 0; l <= max_level; ++l) {
      leaf_parents_.push_back(spool("lp", l));
      required_parents_.push_back(spool("rp", l));
      required_.push_back(spool("r", l));
    }
    BTreeCursor c;
    WEAVER_RETURN_IF_ERROR(leaves_.seek_cursor(0, &c));
    while (c.valid()) {
      const Octant q = octant_from_key(c.key());
      ++r_->input_leaves;
      // Tag: the leaf that asks, for naming violations.
      if (q.level > 0) {
        WEAVER_RETURN_IF_ERROR(
            leaf_parents_[q.level - 1]->add({octant_key(octant_parent(q)), c.key()}));
      }
      WEAVER_RETURN_IF_ERROR(c.next());
    }
    for (int l = max_level - 1; l >= 0; --l) {
      WEAVER_RETURN_IF_ERROR(leaf_parents_[l]->finish());
      WEAVER_RETURN_IF_ERROR(required_parents_[l]->finish());
      KeyTagMerge parents({leaf_parents_[l].get(), required_parents_[l].get()});
      WEAVER_RETURN_IF_ERROR(expand_level(l, parents, propagate));
      leaf_parents_[l].reset();
      required_parents_[l].reset();
    }
    std::vector<KeyTagSource*> levels;
    for (auto& level : required_) {
      WEAVER_RETURN_IF_ERROR(level->finish());
      if (level->size() > 0) levels.push_back(level.get());
    }
    required_merge_ = std::make_unique<KeyTagMerge>(std::move(levels));
    return Status::Ok();
  }

  // The required octants, deduplicated, in key order; tag = a leaf that asks.
  KeyTagSource& required() { return *required_merge_; }

 private:
  std::unique_ptr<SortedSpool> spool(const char* name, int level) const {
    const size_t bytes = std::clamp<uint64_t>(o_.memory_bytes / 512, 4 << 10, 1 << 20);
    return std::make_unique<SortedSpool>(scratch_ + "/" + name + std::to_string(level), bytes);
  }

  // The face and edge neighbours of the level's parents, into candidates.
  // Parents pass through memory in chunks of what fits in a quarter of the
  // budget (16 bytes each in the list, and a key set of twice as many slots);
  // a neighbour that is a parent of the same chunk is skipped (see
  // expand_level).  Any subset may be skipped, and Z-order keeps most
  // neighbours in one chunk.
  Status emit_candidates(KeyTagSource& parents, ExternalSorter& candidates) {
    const size_t quarter = o_.memory_bytes / 4;
    size_t fits = 1024;
    while (2 * fits * sizeof(KeyTag) + KeySet::slots_for(2 * fits) * 8 <= quarter) fits *= 2;
    std::vector<KeyTag> chunk;
    chunk.reserve(fits);
    KeySet chunk_keys;
    auto flush_chunk = [&]() -> Status {
      chunk_keys.reset(chunk.size());
      for (const KeyTag& q : chunk) chunk_keys.add(q.key);
      for (const KeyTag& q : chunk) {
        const Octant po = octant_from_key(q.key);
        for (const auto& d : dirs_) {
          Octant n;
          if (!octant_neighbour(po, d[0], d[1], d[2], &n)) continue;
          const uint64_t nk = octant_key(n);
          if (!chunk_keys.contains(nk)) WEAVER_RETURN_IF_ERROR(candidates.add({nk, q.tag}));
        }
      }
      chunk.clear();
      return Status::Ok();
    };
    KeyTag p;
    bool done = false, has_prev = false;
    uint64_t prev = 0;
    while (true) {
      WEAVER_RETURN_IF_ERROR(next_unique(parents, &prev, &has_prev, &p, &done));
      if (done) break;
      chunk.push_back(p);
      if (chunk.size() == fits) WEAVER_RETURN_IF_ERROR(flush_chunk());
    }
    return flush_chunk();
  }

  // Neighbours of the level-l parents, kept where they meet the domain.  A
  // neighbour that is itself a parent (it has finer children) is resolved
  // already, and its own parent enters the next level through its siblings,
  // so it is skipped: inside refined regions almost every candidate goes.
  Status expand_level(int l, KeyTagSource& parents, bool propagate) {
    ExternalSorter candidates(scratch_ + "/c" + std::to_string(l), o_.memory_bytes / 4);
    WEAVER_RETURN_IF_ERROR(emit_candidates(parents, candidates));
    WEAVER_RETURN_IF_ERROR(candidates.finish());
    DomainProbe probe;
    WEAVER_RETURN_IF_ERROR(probe.open(leaves_));
    bool done = false, has_prev = false;
    uint64_t prev = 0;
    KeyTag n;
    while (true) {
      WEAVER_RETURN_IF_ERROR(next_unique(candidates, &prev, &has_prev, &n, &done));
      if (done) return Status::Ok();
      bool inside = false;
      WEAVER_RETURN_IF_ERROR(probe.overlaps(n.key, &inside));
      if (!inside) continue;
      WEAVER_RETURN_IF_ERROR(required_[l]->add(n));
      ++r_->required;
      if (l > 0 && propagate) {
        WEAVER_RETURN_IF_ERROR(required_parents_[l - 1]->add(
            {octant_key(octant_parent(octant_from_key(n.key))), n.tag}));
      }
    }
  }

  BTree& leaves_;
  const BalanceOptions& o_;
  std::string scratch_;
  BalanceResult* r_;
  std::vector<std::array<int, 3>> dirs_;
  // By level: parents of leaves, parents of required octants, the required.
  std::vector<std::unique_ptr<SortedSpool>> leaf_parents_, required_parents_, required_;
  std::unique_ptr<KeyTagMerge> required_merge_;
};

// Writes leaf t, split just enough that every required octant strictly
// inside it is resolved.  `inside` holds those, in key order.
class Completion {
 public:
  Completion(BTree& out, const VelocityModel* model, double tick_m, uint32_t payload)
      : out_(out), model_(model), tick_m_(tick_m), payload_(payload) {}

  Status write(const Octant& t, const std::byte* parent_payload, const std::vector<KeyTag>& inside,
               BalanceResult* r) {
    size_t pos = 0;
    return split(t, parent_payload, inside, &pos, r);
  }
  Status flush() {
    WEAVER_RETURN_IF_ERROR(out_.append_batch(keys_.data(), payloads_.data(), keys_.size()));
    keys_.clear();
    payloads_.clear();
    return Status::Ok();
  }

 private:
  Status split(const Octant& o, const std::byte* parent_payload, const std::vector<KeyTag>& inside,
               size_t* pos, BalanceResult* r) {
    const uint64_t key = octant_key(o), end = octant_subtree_key_end(o);
    while (*pos < inside.size() && inside[*pos].key <= key) ++*pos;  // o itself is resolved
    if (*pos < inside.size() && inside[*pos].key < end) {
      for (int c = 0; c < 8; ++c) {
        WEAVER_RETURN_IF_ERROR(split(octant_child(o, c), parent_payload, inside, pos, r));
      }
      return Status::Ok();
    }
    return emit(o, parent_payload, r);
  }

  Status emit(const Octant& o, const std::byte* parent_payload, BalanceResult* r) {
    keys_.push_back(octant_key(o));
    const size_t at = payloads_.size();
    payloads_.resize(at + payload_);
    if (payload_ > 0) std::memcpy(payloads_.data() + at, parent_payload, payload_);
    if (model_ != nullptr && payload_ == 12) {  // vp, vs, rho at the new leaf's centre
      const double h = octant_edge(o) * tick_m_ / 2;
      const Material m = model_->at(o.x * tick_m_ + h, o.y * tick_m_ + h, o.z * tick_m_ + h);
      const float f[3] = {m.vp, m.vs, m.rho};
      std::memcpy(payloads_.data() + at, f, sizeof f);
    }
    ++r->levels[o.level];
    ++r->output_leaves;
    if (keys_.size() == kBatch) return flush();
    return Status::Ok();
  }

  BTree& out_;
  const VelocityModel* model_;
  double tick_m_;
  uint32_t payload_;
  std::vector<uint64_t> keys_;
  std::vector<std::byte> payloads_;
};

// The model named in the table's metadata, if it is a built-in one.
std::unique_ptr<VelocityModel> model_of(const std::string& metadata) {
  const size_t at = metadata.find("model=");
  if (at == std::string::npos) return nullptr;
  const std::string name = metadata.substr(at + 6, metadata.find(';', at) - at - 6);
  std::unique_ptr<VelocityModel> m;
  if (name == "grid" || !make_model(name, "", &m).ok()) return nullptr;
  return m;
}

std::string replace_levels(const std::string& metadata, const LevelCounts& levels) {
  std::string out;
  size_t start = 0;
  while (start <= metadata.size()) {  // drop the old ";levels=..." item
    size_t end = metadata.find(';', start);
    if (end == std::string::npos) end = metadata.size();
    const std::string item = metadata.substr(start, end - start);
    if (!item.empty() && item.rfind("levels=", 0) != 0) out += (out.empty() ? "" : ";") + item;
    start = end + 1;
  }
  return out + levels_to_metadata(levels);
}

// Calls visit(leaf cursor, required octants strictly inside the leaf) for
// every leaf in key order, until visit sets *stop.
Status for_each_leaf(BTree& leaves, KeyTagSource& required,
                     const std::function<Status(const BTreeCursor&, const std::vector<KeyTag>&,
                                                bool*)>& visit) {
  BTreeCursor c;
  WEAVER_RETURN_IF_ERROR(leaves.seek_cursor(0, &c));
  KeyTag req;
  bool done = false, has_prev = false, stop = false;
  uint64_t prev = 0;
  WEAVER_RETURN_IF_ERROR(next_unique(required, &prev, &has_prev, &req, &done));
  std::vector<KeyTag> inside;
  while (c.valid() && !stop) {
    const uint64_t key = c.key(), end = octant_key_subtree_end(key);
    inside.clear();
    while (!done && req.key < end) {  // required octants up to the end of this leaf
      if (req.key > key) inside.push_back(req);
      WEAVER_RETURN_IF_ERROR(next_unique(required, &prev, &has_prev, &req, &done));
    }
    WEAVER_RETURN_IF_ERROR(visit(c, inside, &stop));
    WEAVER_RETURN_IF_ERROR(c.next());
  }
  return Status::Ok();
}

// Merges the leaves with the required octants and writes the refinement.
Status write_refinement(BTree& leaves, KeyTagSource& required, BTree& out, BalanceResult* r) {
  Units u;
  units_from_metadata(leaves.options().metadata, &u);
  const std::unique_ptr<VelocityModel> model = model_of(leaves.options().metadata);
  Completion completion(out, model.get(), u.tick_m, leaves.payload_size());
  std::vector<std::byte> payload(leaves.payload_size());
  WEAVER_RETURN_IF_ERROR(for_each_leaf(
      leaves, required, [&](const BTreeCursor& c, const std::vector<KeyTag>& inside, bool*) {
        if (!inside.empty()) ++r->split;
        if (!payload.empty()) std::memcpy(payload.data(), c.payload(), payload.size());
        return completion.write(octant_from_key(c.key()), payload.data(), inside, r);
      }));
  return completion.flush();
}

// The leaf of parent(asker) that touches `coarse`: the leaf holding the
// pixel of parent(asker) nearest to it.  (The asker itself may sit on the far
// side of its parent; the parent is covered by leaves at least as fine.)
Status touching_leaf(BTree& leaves, const Octant& coarse, const Octant& asker, Octant* out) {
  const Octant p = octant_parent(asker);
  const uint32_t s = octant_edge(p), e = octant_edge(coarse);
  const uint32_t lo[3] = {p.x, p.y, p.z}, clo[3] = {coarse.x, coarse.y, coarse.z};
  uint32_t px[3];
  for (int a = 0; a < 3; ++a) {
    if (clo[a] >= lo[a] + s) {
      px[a] = lo[a] + s - 1;  // coarse lies beyond on this axis
    } else if (clo[a] + e <= lo[a]) {
      px[a] = lo[a];          // coarse lies before
    } else {
      px[a] = std::max(lo[a], clo[a]);  // overlapping range: a shared coordinate
    }
  }
  uint64_t key = 0;
  bool found = false;
  WEAVER_RETURN_IF_ERROR(leaves.floor(pixel_key({px[0], px[1], px[2]}), &key, nullptr, &found));
  *out = found ? octant_from_key(key) : asker;
  return Status::Ok();
}

// check_only: the first required octant strictly inside a leaf is a violation.
Status find_violation(BTree& leaves, KeyTagSource& required, BalanceResult* r) {
  return for_each_leaf(
      leaves, required, [&](const BTreeCursor& c, const std::vector<KeyTag>& inside, bool* stop) {
        if (inside.empty()) return Status::Ok();
        const Octant coarse = octant_from_key(c.key());
        Octant fine;
        WEAVER_RETURN_IF_ERROR(touching_leaf(leaves, coarse, octant_from_key(inside[0].tag), &fine));
        r->balanced = false;
        r->violation = "octants " + describe_octant(coarse) + " and " + describe_octant(fine) +
                       " are face or edge neighbours more than one level apart";
        *stop = true;
        return Status::Ok();
      });
}

}  // namespace

namespace {

// The finest level with leaves, from the metadata when the writer kept it.
int max_level_of(BTree& leaves) {
  LevelCounts levels{};
  return levels_from_metadata(leaves.options().metadata, &levels) ? finest_level(levels) : kMaxLevel;
}

// Removes the scratch directory of the sorters however the run ends.
struct ScratchGuard {
  std::string dir;
  ~ScratchGuard() {
    std::error_code ec;
    std::filesystem::remove_all(dir, ec);
  }
};

}  // namespace

Status check_balance(BTree& leaves, const BalanceOptions& o, const std::string& scratch_parent,
                     BalanceResult* r) {
  *r = BalanceResult{};
  ScratchGuard guard{scratch_parent + "/weaver-balance-check-" + std::to_string(::getpid())};
  Balancer balancer(leaves, o, guard.dir, r);
  WEAVER_RETURN_IF_ERROR(balancer.closure(max_level_of(leaves), false));
  return find_violation(leaves, balancer.required(), r);
}

Status balance_octree(const std::string& db_dir, const BalanceOptions& o, BalanceResult* r) {
  *r = BalanceResult{};
  std::unique_ptr<Database> db;
  WEAVER_RETURN_IF_ERROR(Database::open(db_dir, o.check_only ? Database::Mode::kRead
                                                             : Database::Mode::kWrite,
                                        false, &db));
  std::unique_ptr<BTree> leaves;
  WEAVER_RETURN_IF_ERROR(db->open_table(kOctantTable, std::min<uint64_t>(o.memory_bytes / 8, 32ull << 20), &leaves));
  // A reader keeps its scratch out of the database directory, where a
  // writer's open would remove it as a leftover.
  if (o.check_only) {
    return check_balance(*leaves, o, std::filesystem::temp_directory_path().string(), r);
  }
  ScratchGuard guard{db_dir + "/tmp-balance-" + std::to_string(::getpid())};
  Balancer balancer(*leaves, o, guard.dir, r);
  WEAVER_RETURN_IF_ERROR(balancer.closure(max_level_of(*leaves), true));
  TableOptions topt = leaves->options();
  std::unique_ptr<BTree> out;
  std::string file;
  WEAVER_RETURN_IF_ERROR(db->create_table(kOctantTable, topt, std::min<uint64_t>(o.memory_bytes / 8, 8ull << 20), &out, &file));
  const Status st = write_refinement(*leaves, balancer.required(), *out, r);
  if (st.ok()) out->set_metadata(replace_levels(leaves->options().metadata, r->levels));
  return db->publish(kOctantTable, file, out, st);
}

}  // namespace weaver
