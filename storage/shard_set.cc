#include "storage/shard_set.h"

#include <algorithm>
#include <string>

namespace weaver {

Status ShardSet::make(std::vector<std::unique_ptr<BTree>> shards, std::unique_ptr<ShardSet>* out) {
  if (shards.empty()) return Status::InvalidArgument("a sharded table needs a shard");
  std::unique_ptr<ShardSet> s(new ShardSet());
  s->before_.push_back(0);
  for (size_t i = 0; i < shards.size(); ++i) {
    BTree& t = *shards[i];
    const std::string name = "shard " + std::to_string(i) + " (" + t.file_name() + ")";
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

// A BTreeCursor in one shard at a time: at a shard's end, the next shard's
// first record.
class ShardSet::ShardCursor final : public Cursor {
 public:
  explicit ShardCursor(ShardSet& set) : set_(set) {}

  // At the first key >= key, from shard i on.
  Status start(size_t i, uint64_t key) {
    shard_ = i;
    WEAVER_RETURN_IF_ERROR(set_.shards_[shard_]->seek_cursor(key, &c_));
    return settle();
  }
  bool valid() const override { return c_.valid(); }
  uint64_t key() const override { return c_.key(); }
  const std::byte* payload() const override { return c_.payload(); }
  Status next() override {
    WEAVER_RETURN_IF_ERROR(c_.next());
    return settle();
  }

 private:
  // Past a shard's last record, on to the next shard's first.
  Status settle() {
    while (!c_.valid() && shard_ + 1 < set_.shards_.size()) {
      ++shard_;
      WEAVER_RETURN_IF_ERROR(set_.shards_[shard_]->seek_cursor(0, &c_));
    }
    return Status::Ok();
  }

  ShardSet& set_;
  size_t shard_ = 0;
  BTreeCursor c_;
};

Status ShardSet::seek(uint64_t key, std::unique_ptr<Cursor>* out) {
  auto c = std::make_unique<ShardCursor>(*this);
  WEAVER_RETURN_IF_ERROR(c->start(static_cast<size_t>(std::max(shard_of(key), 0)), key));
  *out = std::move(c);
  return Status::Ok();
}

}  // namespace weaver
