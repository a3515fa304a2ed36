#include "balance/refinement.h"

#include <cstring>
#include <vector>

#include "balance/closure.h"
#include "db/async_append.h"
#include "util/resolve_split.h"

namespace weaver {
namespace {

constexpr size_t kBatch = 4096;

// Writes leaf t, split just enough that every required octant strictly
// inside it is resolved.  `inside` holds those, in key order.  Pages are
// encoded and written on the appender's thread (given more than one),
// alongside this one's reading, splitting and filling in new leaves'
// material: the appender has the larger share of the work (at 1 Hz it was busy 61% of the samples
// of the refinement when it filled the material too, this thread 39%).
class Completion {
 public:
  Completion(BTree& out, bool appender_thread, const FillPayload& fill, uint32_t payload)
      : out_(out, appender_thread), fill_(payload > 0 ? fill : nullptr), payload_(payload) {}

  Status write(uint64_t key, const std::byte* parent_payload, const std::vector<KeyTag>& inside,
               BalanceResult* r) {
    size_t pos = 0;
    return split_to_resolve(
        key, false, inside.size(), [&](size_t i) { return inside[i].key; }, &pos,
        [&](uint64_t leaf, bool is_new) { return emit(leaf, is_new, parent_payload, r); });
  }
  // A leaf with nothing required inside it (nearly all of them): copied
  // from its key and payload as they are, without decoding the octant.
  Status copy(uint64_t key, const std::byte* payload, BalanceResult* r) {
    add_entry(key, octant_key_level(key), payload, r);
    return flush_if_full();
  }
  Status flush() { return out_.append(&batch_); }
  Status finish() {
    WEAVER_RETURN_IF_ERROR(flush());
    return out_.finish();
  }

 private:
  // is_new: o is a child made by a split, not a leaf of the input.
  Status emit(uint64_t key, bool is_new, const std::byte* parent_payload, BalanceResult* r) {
    add_entry(key, octant_key_level(key), parent_payload, r);
    if (is_new && fill_ && !fill_(octant_from_key(key), &*(batch_.payloads.end() - payload_))) {
      drop_last(r);
      return Status::Ok();
    }
    return flush_if_full();
  }
  void drop_last(BalanceResult* r) {
    --r->levels[octant_key_level(batch_.keys.back())];
    --r->output_leaves;
    batch_.keys.pop_back();
    batch_.payloads.resize(batch_.payloads.size() - payload_);
  }

  // Adds a leaf to the batch with a copy of `payload`.
  void add_entry(uint64_t key, int level, const std::byte* payload, BalanceResult* r) {
    batch_.keys.push_back(key);
    batch_.payloads.insert(batch_.payloads.end(), payload, payload + payload_);
    ++r->levels[level];
    ++r->output_leaves;
  }
  Status flush_if_full() { return batch_.keys.size() == kBatch ? flush() : Status::Ok(); }

  AsyncAppender out_;
  FillPayload fill_;  // gives new leaves their own payload, if set
  uint32_t payload_;
  AsyncAppender::Batch batch_;
};

}  // namespace

Status write_refinement(BTree& leaves, KeyTagSource& required, const FillPayload& fill, BTree& out,
                        int threads, BalanceProgress* progress, BalanceResult* r,
                        uint64_t keep_from, uint64_t keep_to) {
  uint64_t read = 0;
  Completion completion(out, threads > 1, fill, leaves.payload_size());
  std::vector<std::byte> payload(leaves.payload_size());
  WEAVER_RETURN_IF_ERROR(for_each_leaf(
      leaves, required, [&](const BTreeCursor& c, const std::vector<KeyTag>& inside, bool*) {
        if (progress != nullptr) progress->refined(++read);
        if (c.key() < keep_from || c.key() >= keep_to) return Status::Ok();
        if (inside.empty()) return completion.copy(c.key(), c.payload(), r);
        ++r->split;
        if (!payload.empty()) std::memcpy(payload.data(), c.payload(), payload.size());
        return completion.write(c.key(), payload.data(), inside, r);
      }));
  return completion.finish();
}

}  // namespace weaver
