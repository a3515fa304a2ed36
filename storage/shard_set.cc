#include "storage/shard_set.h"

#include <algorithm>
#include <string>

namespace weaver {
namespace {

// A sharded tree reads nothing itself: its shards hold the pages.
class NoFile final : public File {
 public:
  explicit NoFile(std::string name) : name_(std::move(name)) {}
  Status read_at(uint64_t, void*, size_t, size_t*) override { return refuse(); }
  Status write_at(uint64_t, const void*, size_t, size_t*) override { return refuse(); }
  Status sync() override { return Status::Ok(); }
  Status size(uint64_t* out) override { return *out = 0, Status::Ok(); }
  Status truncate(uint64_t) override { return refuse(); }
  const std::string& name() const override { return name_; }

 private:
  Status refuse() const { return Status::InvalidArgument(name_ + ": read through its shards"); }
  std::string name_;
};

std::string shard_name(size_t i, const BTree& t) {
  return "shard " + std::to_string(i) + " (" + t.file_name() + ")";
}

}  // namespace

Status ShardSet::make(std::vector<std::unique_ptr<BTree>> shards, std::unique_ptr<ShardSet>* out) {
  if (shards.empty()) return Status::InvalidArgument("a sharded table needs a shard");
  std::unique_ptr<ShardSet> s(new ShardSet());
  s->before_.push_back(0);
  for (size_t i = 0; i < shards.size(); ++i) {
    BTree& t = *shards[i];
    const std::string name = shard_name(i, t);
    if (t.size() == 0) return Status::Corruption(name + " is empty");
    if (t.payload_size() != shards[0]->payload_size()) {
      return Status::Corruption(name + " has records of another size");
    }
    uint64_t first = 0, last = 0;
    WEAVER_RETURN_IF_ERROR(t.select(0, &first, nullptr));
    WEAVER_RETURN_IF_ERROR(t.select(t.size() - 1, &last, nullptr));
    if (i > 0 && first <= s->last_.back()) {
      return Status::Corruption(name + " starts at or before the end of the shard before it");
    }
    s->first_.push_back(first);
    s->last_.push_back(last);
    s->before_.push_back(s->before_.back() + t.size());
  }
  for (size_t i = 0; i + 1 < shards.size(); ++i) shards[i]->next_shard_ = shards[i + 1].get();
  s->shards_ = std::move(shards);
  *out = std::move(s);
  return Status::Ok();
}

int ShardSet::shard_of(uint64_t key) const {
  return static_cast<int>(std::upper_bound(first_.begin(), first_.end(), key) - first_.begin()) - 1;
}

Status ShardSet::get(uint64_t key, std::byte* payload_out, bool* found) {
  const int i = shard_of(key);
  if (i < 0) return *found = false, Status::Ok();
  return shards_[i]->get(key, payload_out, found);
}

Status ShardSet::floor(uint64_t key, uint64_t* key_out, std::byte* payload_out, bool* found) {
  const int i = shard_of(key);  // its first key is <= key: the floor is in it
  if (i < 0) return *found = false, Status::Ok();
  return shards_[i]->floor(key, key_out, payload_out, found);
}

Status ShardSet::rank_exact(uint64_t key, uint64_t* rank, bool* present) {
  const int i = shard_of(key);
  if (i < 0) {
    *rank = 0, *present = false;
    return Status::Ok();
  }
  uint64_t local = 0;
  WEAVER_RETURN_IF_ERROR(shards_[i]->rank_exact(key, &local, present));
  *rank = before_[i] + local;
  return Status::Ok();
}

Status ShardSet::select(uint64_t index, uint64_t* key_out, std::byte* payload_out) {
  if (index >= size()) {
    return Status::InvalidArgument("record " + std::to_string(index) + " does not exist (" +
                                   std::to_string(size()) + " records)");
  }
  // The shard whose range of ranks holds index: before_[i] <= index < before_[i + 1].
  const size_t i = std::upper_bound(before_.begin(), before_.end(), index) - before_.begin() - 1;
  return shards_[i]->select(index - before_[i], key_out, payload_out);
}

Status ShardSet::leaf_keys(uint64_t key, std::vector<uint64_t>* keys, uint64_t* first_rank,
                           std::vector<std::byte>* payloads) {
  // Below every shard, the first shard's first leaf is where key would be;
  // between two shards, the earlier one's last leaf (its ranks end where
  // the next shard's begin).
  const size_t i = static_cast<size_t>(std::max(shard_of(key), 0));
  WEAVER_RETURN_IF_ERROR(shards_[i]->leaf_keys(key, keys, first_rank, payloads));
  *first_rank += before_[i];
  return Status::Ok();
}

Status ShardSet::position(uint64_t key, bool keys_only, BTreeCursor* cursor) {
  BTree& t = *shards_[static_cast<size_t>(std::max(shard_of(key), 0))];
  return keys_only ? t.seek_keys(key, cursor) : t.seek_cursor(key, cursor);
}

Status ShardSet::check_invariants() {
  for (size_t i = 0; i < shards_.size(); ++i) {
    const Status st = shards_[i]->check_invariants();
    if (!st.ok()) return Status::Corruption(shard_name(i, *shards_[i]) + ": " + st.message());
  }
  return Status::Ok();  // the order between shards was checked by make
}

Status BTree::open_sharded(std::vector<std::unique_ptr<BTree>> shards,
                           std::unique_ptr<BTree>* out) {
  std::unique_ptr<ShardSet> set;
  WEAVER_RETURN_IF_ERROR(ShardSet::make(std::move(shards), &set));
  BTree& first = set->shard(0);
  const std::string name = first.file_name() + " and " + std::to_string(set->shard_count() - 1) +
                           " more shard" + (set->shard_count() == 2 ? "" : "s");
  // The smallest pool: the tree itself never reads a page.
  std::unique_ptr<BTree> t(new BTree(std::make_unique<NoFile>(name), first.options(), 0));
  for (size_t i = 0; i < set->shard_count(); ++i) {
    const BTree& s = set->shard(i);
    t->height_ = std::max(t->height_, s.height());
    t->page_count_ += s.page_count();
  }
  t->record_count_ = set->size();
  t->shard_headers_ = static_cast<uint32_t>(set->shard_count());
  t->shards_ = std::move(set);
  *out = std::move(t);
  return Status::Ok();
}

size_t BTree::shard_count() const { return shards_ ? shards_->shard_count() : 0; }

}  // namespace weaver
