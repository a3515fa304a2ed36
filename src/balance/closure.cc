#include "balance/closure.h"

#include <algorithm>
#include <array>
#include <bit>
#include <filesystem>

#include "balance/forward_floor.h"
#include "schema/octant.h"
#include "sort/external_sort.h"
#include "util/key_set.h"
#include "util/parallel.h"
#include "util/parent_asks.h"

namespace weaver {
namespace {

// Tells whether each of a nondecreasing stream of octants overlaps the
// domain (the union of the leaves).  The domain map answers first; the
// table is asked (forward_floor.h) only about octants in the map's cells
// that the leaves cover in part.
class DomainProbe {
 public:
  Status open(BTree& leaves, const DomainMap& map) {
    map_ = &map;
    return floor_.open(leaves);
  }
  Status overlaps(uint64_t key, bool* yes) {
    const DomainMap::Answer a = map_->overlaps(key);
    if (a != DomainMap::Answer::kAskTheLeaves) {
      *yes = a == DomainMap::Answer::kYes;
      return Status::Ok();
    }
    WEAVER_RETURN_IF_ERROR(floor_.advance_to(key));
    // A leaf equal to or containing the octant, or a leaf inside it.
    *yes = (floor_.has_last() && key < octant_key_subtree_end(floor_.last())) ||
           (floor_.has_next() && floor_.next_key() < octant_key_subtree_end(key));
    return Status::Ok();
  }

  // Whether the octant lies in one leaf bigger than itself (the keys asked,
  // here and of overlaps, nondecreasing).
  Status strictly_inside_a_leaf(uint64_t key, bool* yes) {
    WEAVER_RETURN_IF_ERROR(floor_.advance_to(key));
    *yes = floor_.has_last() && floor_.last() != key && key < octant_key_subtree_end(floor_.last());
    return Status::Ok();
  }

 private:
  const DomainMap* map_ = nullptr;
  ForwardFloor floor_;
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

}  // namespace

Closure::Closure(BTree& leaves, const BalanceMemory& memory, const std::string& scratch_dir,
                 const BalanceOptions& options, BalanceProgress* progress, BalanceResult* result,
                 BTree* second_reader)
    : leaves_(leaves),
      second_reader_(second_reader),
      memory_(memory),
      scratch_(scratch_dir),
      threads_(std::max(1, options.threads)),
      parallel_chunk_(options.parallel_chunk),
      progress_(progress),
      r_(result) {}

Closure::~Closure() = default;

Status Closure::build(int max_level, bool propagate) {
  for (int l = 0; l <= max_level; ++l) {
    required_parents_.push_back(spool("rp", l));
    required_.push_back(spool("r", l));
  }
  WEAVER_RETURN_IF_ERROR(scan_leaves(max_level));
  for (int l = max_level - 1; l >= 0; --l) {
    WEAVER_RETURN_IF_ERROR(required_parents_[l]->finish());
    std::vector<KeyTagSource*> sources = {required_parents_[l].get()};
    uint64_t parent_count = required_parents_[l]->size();
    for (Spools& stretch : leaf_parents_) {
      WEAVER_RETURN_IF_ERROR(stretch[l]->finish());
      sources.push_back(stretch[l].get());
      parent_count += stretch[l]->size();
    }
    KeyTagMerge parents(std::move(sources));
    WEAVER_RETURN_IF_ERROR(expand_level(l, parents, parent_count, propagate));
    for (Spools& stretch : leaf_parents_) stretch[l].reset();
    required_parents_[l].reset();
    if (progress_ != nullptr) progress_->level_done(l);
  }
  std::vector<KeyTagSource*> levels;
  for (auto& level : required_) {
    WEAVER_RETURN_IF_ERROR(level->finish());
    if (level->size() > 0) levels.push_back(level.get());
  }
  required_merge_ = std::make_unique<KeyTagMerge>(std::move(levels));
  return Status::Ok();
}

// The first scan: every leaf into the domain map, and the parents of the
// leaves, each with the set of its children that are leaves, into the
// spools of their level.  Given a second reader it runs as two stretches of
// key order on two threads, cut near the median leaf where the map's words
// part (DomainMap::stretch_start).  A parent cut in two gets an entry from
// each stretch; the level pass merges them.
Status Closure::scan_leaves(int max_level) {
  domain_ = std::make_unique<DomainMap>(DomainMap::level_for(memory_.domain_map, max_level));
  uint64_t cut = 0;
  if (second_reader_ != nullptr && threads_ > 1 && leaves_.size() >= 2 * parallel_chunk_) {
    uint64_t median = 0;
    WEAVER_RETURN_IF_ERROR(leaves_.select(leaves_.size() / 2, &median, nullptr));
    cut = domain_->stretch_start(median);
  }
  const int stretches = cut > 0 ? 2 : 1;
  std::vector<DomainMap::Writer> writers(stretches, DomainMap::Writer(domain_.get()));
  for (int i = 0; i < stretches; ++i) {
    leaf_parents_.emplace_back();
    for (int l = 0; l <= max_level; ++l) {
      leaf_parents_[i].push_back(spool("lp" + std::to_string(i) + "-", l));
    }
  }
  std::atomic<uint64_t> scanned{0};
  std::vector<uint64_t> counts(stretches, 0);
  WEAVER_RETURN_IF_ERROR(run_shares(stretches, [&](int i) {
    BTree& reader = i == 0 ? leaves_ : *second_reader_;
    const uint64_t from = i == 0 ? 0 : cut, to = i + 1 < stretches ? cut : ~uint64_t{0};
    return scan_stretch(reader, from, to, leaf_parents_[i], writers[i], &scanned, i == 0,
                        &counts[i]);
  }));
  for (uint64_t n : counts) r_->input_leaves += n;
  return Status::Ok();
}

// The leaves with keys in [from, to).  Leaves of one level under one parent
// come one after another in that level's stream (nothing else of that level
// lies between them in key order), so each level has one open parent, with
// the set of its children so far in its tag.
Status Closure::scan_stretch(BTree& leaves, uint64_t from, uint64_t to, Spools& parents,
                             DomainMap::Writer& map, std::atomic<uint64_t>* scanned, bool report,
                             uint64_t* read) {
  std::vector<KeyTag> open(parents.size(), KeyTag{0, 0});
  uint64_t& count = *read;
  BTreeCursor c;
  WEAVER_RETURN_IF_ERROR(leaves.seek_keys(from, &c));
  while (c.valid() && c.key() < to) {
    const uint64_t key = c.key();
    map.add_leaf(key);
    if (++count % BalanceProgress::kEvery == 0) {
      const uint64_t all = scanned->fetch_add(BalanceProgress::kEvery) + BalanceProgress::kEvery;
      if (report && progress_ != nullptr) progress_->scanned(all);
    }
    const int level = octant_key_level(key);
    if (level > 0) {
      KeyTag& p = open[level - 1];
      const uint64_t parent = octant_key_parent(key);
      if (p.tag != 0 && p.key != parent) WEAVER_RETURN_IF_ERROR(parents[level - 1]->add(p));
      if (p.tag == 0 || p.key != parent) p = {parent, parent_asks::children_tag(0)};
      p.tag |= parent_asks::children_tag(1u << octant_key_child_id(key));
    }
    WEAVER_RETURN_IF_ERROR(c.next());
  }
  for (size_t l = 0; l < open.size(); ++l) {
    if (open[l].tag != 0) WEAVER_RETURN_IF_ERROR(parents[l]->add(open[l]));
  }
  map.finish();
  return Status::Ok();
}

std::unique_ptr<SortedSpool> Closure::spool(const std::string& name, int level) const {
  return std::make_unique<SortedSpool>(scratch_ + "/" + name + std::to_string(level),
                                       memory_.spool_buffer);
}

// The face and edge neighbours that the level's parents ask for (see
// parent_asks.h), into the candidate sorters.  Parents pass through memory
// in chunks of what fits in the chunk share (17 bytes each in the lists,
// and a key set of four times as many slots); a neighbour that is a parent
// of the same chunk is skipped (see expand_level).  Any subset may be
// skipped, and Z-order keeps most neighbours in one chunk.  A large chunk
// is cut into one share per sorter, each on its own thread; which sorter
// gets a candidate does not change the merged stream.
//
// A candidate's tag names a leaf that asks for it: one of the parent's
// leaves that touches it, or the leaf that a required octant's entry names.
Status Closure::emit_candidates(int l, KeyTagSource& parents, uint64_t parent_count,
                                Sorters& sorters, uint64_t* added) {
  constexpr size_t kEntry = sizeof(KeyTag) + 1;
  size_t fits = 1024;
  while (2 * fits * kEntry + KeySet::slots_for(2 * fits) * 8 <= memory_.parent_chunk) fits *= 2;
  // A parent, with the leaf a required octant's entry named (or 0), and the
  // children that are leaves (all 8 for a parent wholly in the domain).
  // (Room for the level's entries when they are fewer: a chunk the size of
  // the budget, allocated for a few parents, was most of the sanitizers'
  // time in the balance tests.)
  std::vector<KeyTag> chunk;
  std::vector<uint8_t> children;
  chunk.reserve(std::min<uint64_t>(fits, parent_count));
  children.reserve(std::min<uint64_t>(fits, parent_count));
  KeySet chunk_keys;
  std::vector<uint64_t> share_added(sorters.size());
  // Candidates of chunk[begin, end) into `into`.
  auto emit_range = [&](size_t begin, size_t end, ExternalSorter& into, uint64_t* count) {
    for (size_t p = begin; p < end; ++p) {
      const KeyTag& q = chunk[p];
      std::array<uint64_t, kFaceAndEdgeDirections.size()> near;
      std::array<uint8_t, kFaceAndEdgeDirections.size()> direction;
      size_t n = 0;
      for (uint32_t bits = parent_asks::kTouchedBy[children[p]]; bits != 0; bits &= bits - 1) {
        direction[n] = static_cast<uint8_t>(std::countr_zero(bits));
        if (octant_key_neighbour(q.key, kFaceAndEdgeDirections[direction[n]], &near[n])) {
          chunk_keys.prefetch(near[n++]);
        }
      }
      for (size_t i = 0; i < n; ++i) {
        if (chunk_keys.contains(near[i])) continue;
        const unsigned touching = children[p] & parent_asks::kTouching[direction[i]];
        const uint64_t tag =
            q.tag != 0 ? q.tag : octant_key_child(q.key, std::countr_zero(touching));
        WEAVER_RETURN_IF_ERROR(into.add({near[i], tag}));
        ++*count;
      }
    }
    return Status::Ok();
  };
  auto flush_chunk = [&]() -> Status {
    chunk_keys.reset(chunk.size());
    for (const KeyTag& q : chunk) chunk_keys.add(q.key);
    const size_t shares = chunk.size() >= parallel_chunk_ ? sorters.size() : 1;
    WEAVER_RETURN_IF_ERROR(run_shares(static_cast<int>(shares), [&](int i) {
      return emit_range(chunk.size() * i / shares, chunk.size() * (i + 1) / shares, *sorters[i],
                        &share_added[i]);
    }));
    chunk.clear();
    children.clear();
    return Status::Ok();
  };
  // The entries of one parent (one from each spool at most) are merged.
  uint64_t consumed = 0;
  KeyTag p;
  bool done = false;
  while (true) {
    WEAVER_RETURN_IF_ERROR(parents.next(&p, &done));
    if (done) break;
    ++consumed;
    report(l, consumed, 0.5 * double(consumed) / std::max<uint64_t>(parent_count, 1));
    const bool leaves = parent_asks::is_children_tag(p.tag);
    if (chunk.empty() || chunk.back().key != p.key) {
      if (chunk.size() == fits) WEAVER_RETURN_IF_ERROR(flush_chunk());
      chunk.push_back({p.key, 0});
      children.push_back(0);
    }
    if (leaves) {
      children.back() |= static_cast<uint8_t>(parent_asks::children_of(p.tag));
    } else {
      chunk.back().tag = p.tag;
      children.back() = 255;
    }
  }
  WEAVER_RETURN_IF_ERROR(flush_chunk());
  for (uint64_t a : share_added) *added += a;
  return Status::Ok();
}

// Neighbours of the level-l parents, kept where they meet the domain.  A
// neighbour that is itself a parent (it has finer children) is resolved
// already, and its own parent enters the next level through its siblings,
// so it is skipped: inside refined regions almost every candidate goes.
Status Closure::expand_level(int l, KeyTagSource& parents, uint64_t parent_count, bool propagate) {
  // A level too small for any chunk to be shared has one sorter.
  const int shares = parent_count >= parallel_chunk_ ? threads_ : 1;
  Sorters sorters;
  std::vector<KeyTagSource*> sources;
  for (int i = 0; i < shares; ++i) {
    // A parent has a candidate in each face and edge direction at most.
    sorters.push_back(std::make_unique<ExternalSorter>(
        scratch_ + "/c" + std::to_string(l) + "-" + std::to_string(i),
        memory_.candidate_sort / shares, ExternalSorter::Repeats::kFirstOnly,
        parent_count * std::size(kFaceAndEdgeDirections)));
    sources.push_back(sorters.back().get());
  }
  uint64_t added = 0, probed = 0;
  WEAVER_RETURN_IF_ERROR(emit_candidates(l, parents, parent_count, sorters, &added));
  WEAVER_RETURN_IF_ERROR(run_shares(shares, [&](int i) { return sorters[i]->finish(); }));
  KeyTagMerge candidates(std::move(sources));
  DomainProbe probe;
  WEAVER_RETURN_IF_ERROR(probe.open(leaves_, *domain_));
  bool done = false, has_prev = false;
  uint64_t prev = 0;
  KeyTag n;
  while (true) {
    WEAVER_RETURN_IF_ERROR(next_unique(candidates, &prev, &has_prev, &n, &done));
    if (done) return Status::Ok();
    ++probed;
    report(l, probed, 0.5 + 0.5 * double(probed) / std::max<uint64_t>(added, 1));
    bool inside = false;
    WEAVER_RETURN_IF_ERROR(probe.overlaps(n.key, &inside));
    if (!inside) continue;
    WEAVER_RETURN_IF_ERROR(required_[l]->add(n));
    ++r_->required;
    if (l == 0 || !propagate) continue;
    // Once n is resolved, the leaves of its parent are at least as fine as
    // n, and they touch all of the parent's neighbours if the parent lies
    // wholly in the domain: then it asks for them all.  That holds when n
    // lies in a leaf bigger than itself (which the refinement splits: the
    // requirements that must ripple on); the map may know it for others
    // too (asking then is necessary all the same, and saves the search).
    // Otherwise n's leaves are there already and ask for themselves.
    const uint64_t parent = octant_key_parent(n.key);
    bool whole = domain_->covers(parent);
    if (!whole) WEAVER_RETURN_IF_ERROR(probe.strictly_inside_a_leaf(n.key, &whole));
    if (whole) WEAVER_RETURN_IF_ERROR(required_parents_[l - 1]->add({parent, n.tag}));
  }
}

Status for_each_leaf(BTree& leaves, KeyTagSource& required, const LeafVisit& visit) {
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

ScratchDir::~ScratchDir() {
  std::error_code ec;
  std::filesystem::remove_all(path, ec);
}

}  // namespace weaver
