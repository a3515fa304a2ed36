// The B+tree against std::map under long random mixes of every operation,
// with tiny pages (deep trees), several payload sizes, several seeds, commits,
// reopens and a small buffer pool that forces eviction.
#include <gtest/gtest.h>

#include <algorithm>
#include <ext/pb_ds/assoc_container.hpp>
#include <ext/pb_ds/tree_policy.hpp>
#include <map>
#include <random>
#include <vector>

#include "storage/btree.h"
#include "storage/packed_leaf.h"
#include "test_util.h"

namespace weaver {
namespace {

struct Params {
  uint32_t page_size;
  uint32_t payload;
  uint64_t seed;
  uint64_t pool_bytes;
  bool packed = false;
  KeyKind kind = KeyKind::kOctant;  // the keys are arbitrary: valid octant keys or not
};

class BTreeModel : public ::testing::TestWithParam<Params> {
 protected:
  using Map = std::map<uint64_t, std::vector<std::byte>>;
  // The same key set with O(log n) rank and select, to check ours against.
  using OrderTree =
      __gnu_pbds::tree<uint64_t, __gnu_pbds::null_type, std::less<uint64_t>,
                       __gnu_pbds::rb_tree_tag, __gnu_pbds::tree_order_statistics_node_update>;

  void SetUp() override {
    const Params p = GetParam();
    path_ = dir_.file("t.bt");
    TableOptions o;
    o.page_size = p.page_size;
    o.packed = p.packed;
    o.key_kind = p.kind;
    std::string err;
    std::string text;
    if (p.payload > 0) text = "v:u8";
    for (uint32_t i = 1; i < p.payload; ++i) text += ",f" + std::to_string(i) + ":u8";
    o.schema = *RecordSchema::parse(text, &err);
    std::unique_ptr<File> f;
    ASSERT_OK(open_posix_file(path_, OpenMode::kCreateTruncate, &f));
    pool_bytes_ = p.pool_bytes;
    ASSERT_OK(BTree::create(std::move(f), o, pool_bytes_, &tree_));
  }

  void reopen() {
    ASSERT_OK(tree_->commit());
    tree_.reset();
    std::unique_ptr<File> f;
    ASSERT_OK(open_posix_file(path_, OpenMode::kReadWrite, &f));
    ASSERT_OK(BTree::open(std::move(f), pool_bytes_, &tree_));
  }

  std::vector<std::byte> payload_for(uint64_t key, uint64_t version) const {
    std::vector<std::byte> v(GetParam().payload);
    for (size_t i = 0; i < v.size(); ++i) v[i] = std::byte((key * 31 + version * 7 + i) & 0xff);
    return v;
  }

  void check_floor(uint64_t k) {
    uint64_t got_key = 0;
    bool found = false;
    std::vector<std::byte> buf(GetParam().payload + 1);
    ASSERT_OK(tree_->floor(k, &got_key, buf.data(), &found));
    auto it = model_.upper_bound(k);
    ASSERT_EQ(found, it != model_.begin()) << "floor " << k;
    if (found) {
      --it;
      ASSERT_EQ(got_key, it->first);
      ASSERT_TRUE(std::equal(it->second.begin(), it->second.end(), buf.begin()));
    }
    // floor_rank: the same floor, and its rank in the model.
    uint64_t rank = 0, rank_key = 0;
    bool rank_found = false;
    std::vector<std::byte> rank_buf(GetParam().payload + 1);
    ASSERT_OK(tree_->floor_rank(k, &rank_key, rank_buf.data(), &rank, &rank_found));
    ASSERT_EQ(rank_found, found) << "floor_rank " << k;
    if (found) {
      ASSERT_EQ(rank_key, got_key) << "floor_rank " << k;
      ASSERT_EQ(rank, order_.order_of_key(got_key)) << "floor_rank " << k;
      ASSERT_TRUE(std::equal(it->second.begin(), it->second.end(), rank_buf.begin()));
    }
    // floor_block: when it gives a block, its keys are the model's run from
    // the block's first key on, that run holds k's floor, and every key from
    // the first to the limit has its floor among them.
    uint64_t block[page::kPackedBlock], limit = 0;
    uint32_t count = 0;
    ASSERT_OK(tree_->floor_block(k, block, &count, &limit));
    if (!GetParam().packed) {
      ASSERT_EQ(count, 0u) << "floor_block " << k;
    }
    if (count == 0) return;
    ++blocks_given_;
    ASSERT_TRUE(found) << "floor_block " << k;
    ASSERT_LE(block[0], k);
    ASSERT_LT(k, limit);
    auto run = model_.find(block[0]);
    for (uint32_t i = 0; i < count; ++i, ++run) {
      ASSERT_NE(run, model_.end()) << "floor_block " << k;
      ASSERT_EQ(block[i], run->first) << "floor_block " << k << " key " << i;
    }
    // The next key of the table, if any, is at or past the limit.
    if (run != model_.end()) {
      ASSERT_LE(limit, run->first) << "floor_block " << k;
    }
    ASSERT_GE(limit, block[count - 1] + 1);
  }

  // A walk of floors in ascending key order (floor_rank's walk: a leaf is
  // kept for the floors after it), each checked against the model; with
  // the directory made first half the time (only then are leaves kept).
  // Writes between walks must leave no stale leaf behind.
  void check_walk(std::mt19937_64& rng, uint64_t key_space) {
    if (rng() % 2 == 0) ASSERT_OK(tree_->prepare_lookups());
    std::vector<uint64_t> keys(1 + rng() % 200);
    const uint64_t from = rng() % key_space, span = 1 + rng() % 5000;
    for (uint64_t& k : keys) k = from + rng() % span;
    if (rng() % 8 == 0) keys.push_back(UINT64_MAX);
    std::sort(keys.begin(), keys.end());
    std::vector<std::byte> buf(GetParam().payload + 1);
    for (uint64_t k : keys) {
      uint64_t got = 0, rank = 0;
      bool found = false;
      ASSERT_OK(tree_->floor_rank(k, &got, buf.data(), &rank, &found, true));
      auto it = model_.upper_bound(k);
      ASSERT_EQ(found, it != model_.begin()) << "walk " << k;
      if (!found) continue;
      --it;
      ASSERT_EQ(got, it->first) << "walk " << k;
      ASSERT_EQ(rank, order_.order_of_key(got)) << "walk " << k;
      ASSERT_TRUE(std::equal(it->second.begin(), it->second.end(), buf.begin())) << "walk " << k;
    }
  }

  // A cursor, and a keys-only cursor beside it.
  void check_scan(uint64_t from, int steps) {
    BTreeCursor c, keys;
    ASSERT_OK(tree_->seek_cursor(from, &c));
    ASSERT_OK(tree_->seek_keys(from, &keys));
    auto it = model_.lower_bound(from);
    for (int s = 0; s < steps; ++s) {
      ASSERT_EQ(c.valid(), it != model_.end());
      ASSERT_EQ(keys.valid(), it != model_.end());
      if (!c.valid()) return;
      ASSERT_EQ(c.key(), it->first);
      ASSERT_EQ(keys.key(), it->first);
      ASSERT_TRUE(std::equal(it->second.begin(), it->second.end(), c.payload()));
      ASSERT_OK(c.next());
      ASSERT_OK(keys.next());
      ++it;
    }
  }

  // From each position a keys-only cursor reaches, a skip to a key up to
  // 64 records ahead (or just past one) lands on the first key past it and
  // names the one before, or declines (the leaf ends first) and stays.
  void check_skips() {
    std::mt19937_64 rng(model_.size());
    BTreeCursor c;
    ASSERT_OK(tree_->seek_keys(0, &c));
    auto it = model_.begin();
    while (c.valid()) {
      ASSERT_EQ(c.key(), it->first);
      auto target = it;
      for (uint64_t n = rng() % 64; n > 0 && std::next(target) != model_.end(); --n) ++target;
      const uint64_t k = target->first + rng() % 2;
      uint64_t last = 0;
      if (c.skip_in_leaf(k, &last)) {
        it = model_.upper_bound(k);
        ASSERT_NE(it, model_.end());
        ASSERT_EQ(c.key(), it->first);
        ASSERT_EQ(last, std::prev(it)->first);
      } else {
        ASSERT_EQ(c.key(), it->first);
        ASSERT_OK(c.next());
        ++it;
      }
    }
    ASSERT_EQ(it, model_.end());
  }

  // From cursors set at random keys, a seek within the leaf to a key up to
  // 64 records either way lands where a seek from the tree lands, or
  // declines (the key lies past the leaf's keys) and stays; the record
  // before it in the leaf is the floor of a key not in the tree.
  void check_leaf_seeks() {
    if (model_.empty()) return;
    std::mt19937_64 rng(model_.size() + 1);
    const uint64_t top = std::prev(model_.end())->first + 2;
    for (int n = 0; n < 300; ++n) {
      BTreeCursor c;
      ASSERT_OK(tree_->seek_cursor(rng() % top, &c));
      if (!c.valid()) continue;
      const uint64_t at = c.key();
      auto from = model_.find(at);
      for (int64_t step = int64_t(rng() % 129) - 64; step != 0 && from != model_.end();) {
        if (step > 0 && std::next(from) != model_.end())
          ++from, --step;
        else if (step < 0 && from != model_.begin())
          --from, ++step;
        else
          break;
      }
      const uint64_t k = from->first + rng() % 2;
      if (!c.seek_in_leaf(k)) {
        ASSERT_EQ(c.key(), at) << "a declined seek stays";
        continue;
      }
      const auto it = model_.lower_bound(k);
      ASSERT_NE(it, model_.end());
      ASSERT_EQ(c.key(), it->first);
      ASSERT_TRUE(std::equal(it->second.begin(), it->second.end(), c.payload()));
      uint64_t before = 0;
      const std::byte* payload = nullptr;
      if (c.before_in_leaf(&before, &payload)) {
        ASSERT_NE(it, model_.begin());
        ASSERT_EQ(before, std::prev(it)->first);
        ASSERT_TRUE(
            std::equal(std::prev(it)->second.begin(), std::prev(it)->second.end(), payload));
      }
    }
  }

  // Cursors keeping decoded leaves (a budget below one leaf, so every load
  // evicts, and one of dozens), sent back and forth over the tree by
  // seeks and scans, read what a plain cursor reads.
  void check_kept_leaves() {
    if (model_.empty()) return;
    std::mt19937_64 rng(model_.size() + 2);
    const uint64_t top = std::prev(model_.end())->first + 2;
    for (size_t budget : {size_t{1}, size_t{256} << 10}) {
      DecodedLeaves leaves(budget);
      BTreeCursor c;
      c.keep_decoded(&leaves);
      for (int n = 0; n < 24; ++n) {
        const uint64_t from = rng() % top;
        ASSERT_OK(tree_->seek_cursor(from, &c));
        auto it = model_.lower_bound(from);
        for (int s = int(rng() % 700); s > 0; --s) {
          ASSERT_EQ(c.valid(), it != model_.end());
          if (!c.valid()) break;
          ASSERT_EQ(c.key(), it->first) << "budget " << budget;
          ASSERT_TRUE(std::equal(it->second.begin(), it->second.end(), c.payload()));
          ASSERT_OK(c.next());
          ++it;
        }
      }
    }
  }

  void check_lookups(uint64_t k);

  void check_everything() {
    ASSERT_OK(tree_->check_invariants());
    ASSERT_EQ(tree_->size(), model_.size());
    check_scan(0, static_cast<int>(model_.size()) + 1);
    check_skips();
    check_leaf_seeks();
    check_kept_leaves();
  }

  testing::TempDir dir_;
  std::string path_;
  uint64_t pool_bytes_ = 0;
  std::unique_ptr<BTree> tree_;
  Map model_;
  uint64_t blocks_given_ = 0;  // floor_block's answers with a block
  OrderTree order_;
};

TEST_P(BTreeModel, RandomMixMatchesStdMap) {
  const Params p = GetParam();
  std::mt19937_64 rng(p.seed);
  const uint64_t ops = testing::scaled(400'000, 40'000);
  const uint64_t key_space = 200'000;
  uint64_t version = 0;
  std::vector<std::byte> buf(p.payload + 1);
  for (uint64_t op = 0; op < ops; ++op) {
    const uint64_t r = rng() % 100;
    ++version;
    if (r < 8) {  // append
      const uint64_t k = model_.empty() ? rng() % 1000 : model_.rbegin()->first + 1 + rng() % 50;
      const auto v = payload_for(k, version);
      ASSERT_OK(tree_->append(k, v.data()));
      model_[k] = v;
      order_.insert(k);
    } else if (r < 12) {                // append a batch (sometimes one with a key out of order)
      const size_t n = 1 + rng() % 20;  // crosses leaves: tiny pages hold 3 to 14 records
      uint64_t k = model_.empty() ? rng() % 1000 : model_.rbegin()->first + 1 + rng() % 50;
      std::vector<uint64_t> keys;
      std::vector<std::byte> payloads;
      for (size_t i = 0; i < n; ++i, k += 1 + rng() % 5) {
        keys.push_back(k);
        const auto v = payload_for(k, version);
        payloads.insert(payloads.end(), v.begin(), v.end());
      }
      const bool spoil = n > 2 && rng() % 8 == 0;
      if (spoil) keys[n / 2] = keys[n / 2 - 1];
      const Status st = tree_->append_batch(keys.data(), payloads.data(), n);
      if (spoil) {
        ASSERT_TRUE(st.is_invalid_argument()) << st.to_string();
      } else {
        ASSERT_OK(st);
        for (size_t i = 0; i < n; ++i) {
          model_[keys[i]] = payload_for(keys[i], version);
          order_.insert(keys[i]);
        }
      }
    } else if (r < 14 && !model_.empty()) {  // append out of order: rejected, no change
      const uint64_t k = model_.rbegin()->first - rng() % 3;
      const auto v = payload_for(k, version);
      EXPECT_TRUE(tree_->append(k, v.data()).is_invalid_argument());
    } else if (r < 45) {  // put (insert or update)
      const uint64_t k = rng() % key_space;
      const auto v = payload_for(k, version);
      bool replaced = false;
      ASSERT_OK(tree_->put(k, v.data(), &replaced));
      ASSERT_EQ(replaced, model_.count(k) == 1);
      model_[k] = v;
      order_.insert(k);
    } else if (r < 65) {  // erase, mostly of present keys
      uint64_t k = rng() % key_space;
      if (!model_.empty() && rng() % 4 != 0) {
        auto it = model_.lower_bound(k);
        if (it == model_.end()) it = model_.begin();
        k = it->first;
      }
      const Status st = tree_->erase(k);
      ASSERT_EQ(st.is_not_found(), model_.count(k) == 0) << st.to_string();
      if (st.ok()) {
        model_.erase(k);
        order_.erase(k);
      }
    } else if (r < 75) {  // get
      const uint64_t k = rng() % key_space;
      bool found = false;
      ASSERT_OK(tree_->get(k, buf.data(), &found));
      ASSERT_EQ(found, model_.count(k) == 1);
      if (found) {
        ASSERT_TRUE(std::equal(model_[k].begin(), model_[k].end(), buf.begin()));
      }
    } else if (r < 85) {
      ASSERT_NO_FATAL_FAILURE(check_floor(rng() % (key_space + 1000)));
    } else if (r < 88) {
      ASSERT_NO_FATAL_FAILURE(check_scan(rng() % key_space, 1 + rng() % 300));
    } else if (r < 90) {
      ASSERT_NO_FATAL_FAILURE(check_walk(rng, key_space));
    } else if (r < 96) {  // rank
      const uint64_t k = rng() % key_space;
      uint64_t got = 0;
      ASSERT_OK(tree_->rank(k, &got));
      ASSERT_EQ(got, order_.order_of_key(k));
    } else if (!model_.empty()) {  // select
      const uint64_t i = rng() % model_.size();
      uint64_t key = 0;
      ASSERT_OK(tree_->select(i, &key, buf.data()));
      ASSERT_EQ(key, *order_.find_by_order(i));
    }
    if (op % 20000 == 19999) {
      ASSERT_NO_FATAL_FAILURE(check_everything());
    }
    if (op % 50000 == 49999) {
      ASSERT_NO_FATAL_FAILURE(reopen());
    }
  }
  ASSERT_NO_FATAL_FAILURE(reopen());
  ASSERT_NO_FATAL_FAILURE(check_everything());
  // Packed trees answered most floors from a block.
  if (GetParam().packed) {
    EXPECT_GT(blocks_given_, 1000u);
  }
  // Drain to empty and refill: the empty-tree paths.
  while (!model_.empty()) {
    ASSERT_OK(tree_->erase(model_.begin()->first));
    model_.erase(model_.begin());
  }
  order_.clear();
  ASSERT_NO_FATAL_FAILURE(check_everything());
  ASSERT_EQ(tree_->height(), 0u);
  for (uint64_t k = 0; k < 1000; ++k) ASSERT_OK(tree_->append(k * 3, payload_for(k, 0).data()));
  ASSERT_NO_FATAL_FAILURE(reopen());
  ASSERT_EQ(tree_->size(), 1000u);
  ASSERT_OK(tree_->check_invariants());
}

// Every point lookup against the model in a read burst long enough for the
// tree to build its leaf directory (storage/leaf_directory.h), after changes
// that leave stale separators (erased first keys) and split leaves.
void BTreeModel::check_lookups(uint64_t k) {
  std::vector<std::byte> buf(GetParam().payload + 1);
  bool found = false;
  ASSERT_OK(tree_->get(k, buf.data(), &found));
  ASSERT_EQ(found, model_.count(k) == 1) << "get " << k;
  if (found) {
    ASSERT_TRUE(std::equal(model_[k].begin(), model_[k].end(), buf.begin()));
  }
  ASSERT_NO_FATAL_FAILURE(check_floor(k));
  uint64_t rank = 0;
  bool present = false;
  ASSERT_OK(tree_->rank_exact(k, &rank, &present));
  ASSERT_EQ(rank, order_.order_of_key(k)) << "rank " << k;
  ASSERT_EQ(present, found);
  // leaf_keys: a run of the model's keys, ranked right, whose gap to its
  // neighbours holds k (the leaf the tree routes k to).
  std::vector<uint64_t> keys;
  std::vector<std::byte> payloads;
  uint64_t first = 0;
  ASSERT_OK(tree_->leaf_keys(k, &keys, &first, &payloads));
  if (model_.empty()) return;
  ASSERT_FALSE(keys.empty());
  ASSERT_EQ(first, order_.order_of_key(keys.front()));
  auto it = model_.find(keys.front());
  ASSERT_NE(it, model_.end());
  if (it != model_.begin()) {
    ASSERT_LT(std::prev(it)->first, k);
  }
  for (size_t i = 0; i < keys.size(); ++i, ++it) {
    ASSERT_EQ(keys[i], it->first);
    ASSERT_TRUE(std::equal(it->second.begin(), it->second.end(),
                           payloads.begin() + i * GetParam().payload));
  }
  if (it != model_.end()) {
    ASSERT_GT(it->first, k);
  }
}

TEST_P(BTreeModel, ReadBurstsBetweenChangesMatchStdMap) {
  const Params p = GetParam();
  std::mt19937_64 rng(p.seed + 100);
  const uint64_t key_space = 60'000;
  // Pools of 1 MiB get room for the directory of the deepest trees (128-byte
  // pages); the smaller ones stay too small for one.
  const bool roomy = p.pool_bytes >= (1 << 20);
  if (roomy) {
    pool_bytes_ = 16 << 20;
    ASSERT_NO_FATAL_FAILURE(reopen());
  }
  bool built_once = false;
  for (int round = 0; round < 6; ++round) {
    // Changes: inserts, then erases of present keys (some the first of a leaf).
    for (int i = 0; i < (round == 0 ? 20'000 : 300); ++i) {
      const uint64_t k = rng() % key_space;
      ASSERT_OK(tree_->put(k, payload_for(k, round).data(), nullptr));
      model_[k] = payload_for(k, round);
      order_.insert(k);
    }
    for (int i = 0; i < (round == 0 ? 4'000 : 100) && !model_.empty(); ++i) {
      auto it = model_.lower_bound(rng() % key_space);
      if (it == model_.end()) it = model_.begin();
      ASSERT_OK(tree_->erase(it->first));
      order_.erase(it->first);
      model_.erase(it);
    }
    ASSERT_EQ(tree_->directory_leaves(), 0u) << "a change drops the directory";
    if (round == 3) {
      ASSERT_NO_FATAL_FAILURE(reopen());
    }
    // Every other round the directory is asked for up front (a server about
    // to answer lookups): built at once where the budget allows it.
    if (round % 2 == 1 && !model_.empty()) {
      ASSERT_OK(tree_->prepare_lookups());
      const bool fits =
          LeafDirectory::bytes_for(tree_->page_count()) <= pool_bytes_ / BTree::kDirectoryShare;
      ASSERT_EQ(tree_->directory_leaves() > 0, fits) << "prepare_lookups";
    }
    // The burst: edges, present keys, their neighbours, random keys.
    std::vector<uint64_t> probes = {0, 1, key_space, UINT64_MAX - 1, UINT64_MAX};
    for (auto it = model_.begin(); it != model_.end(); ++it) {
      if (rng() % 8 != 0) continue;
      probes.insert(probes.end(), {it->first - 1, it->first, it->first + 1});
    }
    for (int i = 0; i < 4000; ++i) probes.push_back(rng() % (key_space + 100));
    for (const uint64_t k : probes) ASSERT_NO_FATAL_FAILURE(check_lookups(k));
    if (LeafDirectory::bytes_for(tree_->page_count()) <= pool_bytes_ / BTree::kDirectoryShare) {
      ASSERT_GT(tree_->directory_leaves(), 0u) << "the burst builds the directory";
      built_once = true;
    } else {
      ASSERT_EQ(tree_->directory_leaves(), 0u) << "no room in the budget";
    }
    // Again, now through the directory where there is one.
    for (const uint64_t k : probes) ASSERT_NO_FATAL_FAILURE(check_lookups(k));
  }
  ASSERT_EQ(built_once, roomy);
  ASSERT_NO_FATAL_FAILURE(check_everything());
}

// A directory built by one tree serves another open on the same file in the
// same state (weaver serve's threads share one), whose own budget has no
// room for one: its lookups still match the model, and a change to the
// tree that built it drops it there alone.
TEST_P(BTreeModel, ASharedDirectoryAnswersAsTheTreesOwn) {
  const Params p = GetParam();
  std::mt19937_64 rng(p.seed + 200);
  const uint64_t key_space = 60'000;
  for (int i = 0; i < 20'000; ++i) {
    const uint64_t k = rng() % key_space;
    ASSERT_OK(tree_->put(k, payload_for(k, 0).data(), nullptr));
    model_[k] = payload_for(k, 0);
    order_.insert(k);
  }
  ASSERT_NO_FATAL_FAILURE(reopen());
  tree_->set_directory_budget(64 << 20);
  ASSERT_OK(tree_->prepare_lookups());
  ASSERT_GT(tree_->directory_leaves(), 0u);
  std::unique_ptr<BTree> builder = std::move(tree_);
  std::unique_ptr<File> f;
  ASSERT_OK(open_posix_file(path_, OpenMode::kReadOnly, &f));
  ASSERT_OK(BTree::open(std::move(f), 16 << 10, &tree_));
  tree_->set_directory_budget(0);
  ASSERT_OK(tree_->prepare_lookups());
  ASSERT_EQ(tree_->directory_leaves(), 0u) << "no room of its own";
  tree_->share_directory(builder->directory());
  ASSERT_EQ(tree_->directory_leaves(), builder->directory_leaves());
  std::vector<uint64_t> probes = {0, 1, key_space, UINT64_MAX};
  for (auto it = model_.begin(); it != model_.end(); ++it) {
    if (rng() % 8 == 0) probes.insert(probes.end(), {it->first - 1, it->first, it->first + 1});
  }
  for (int i = 0; i < 4000; ++i) probes.push_back(rng() % (key_space + 100));
  for (const uint64_t k : probes) ASSERT_NO_FATAL_FAILURE(check_lookups(k));
  ASSERT_OK(builder->put(key_space + 7, payload_for(key_space + 7, 1).data(), nullptr));
  EXPECT_EQ(builder->directory_leaves(), 0u);
  EXPECT_GT(tree_->directory_leaves(), 0u);
}

INSTANTIATE_TEST_SUITE_P(
    PagesPayloadsSeeds, BTreeModel,
    ::testing::Values(Params{128, 0, 1, 1 << 20}, Params{128, 16, 2, 16 << 10},
                      Params{256, 8, 3, 1 << 20}, Params{512, 3, 4, 64 << 10},
                      Params{4096, 16, 5, 8 << 20}, Params{128, 24, 6, 1 << 20},
                      // Packed leaves: tiny pages split and re-pack all the time.
                      Params{128, 0, 7, 1 << 20, true}, Params{256, 3, 8, 16 << 10, true},
                      Params{512, 8, 9, 1 << 20, true, KeyKind::kNode},
                      Params{1024, 16, 10, 16 << 10, true}),
    [](const ::testing::TestParamInfo<Params>& info) {
      return std::string(info.param.packed ? "packed_" : "") + "page" +
             std::to_string(info.param.page_size) + "_payload" +
             std::to_string(info.param.payload) + "_seed" + std::to_string(info.param.seed);
    });

}  // namespace
}  // namespace weaver
