#include "storage/lsm_merge.h"

namespace weaver {

Status LsmMergeIterator::init(LsmTree& tree, size_t first_run, bool with_memtable, uint64_t from,
                              bool keep_tombstones) {
  mem_ = &tree.mem_;
  on_shadow_ = &tree.o_.on_shadow;
  keep_tombstones_ = keep_tombstones;
  sources_.clear();
  sources_.reserve(tree.runs_.size() - first_run + 1);
  if (with_memtable && !tree.mem_.empty()) {
    Source s;
    s.mem = true;
    s.pos = tree.mem_.lower_bound(from);
    s.valid = s.pos < tree.mem_.size();
    sources_.push_back(std::move(s));
  }
  for (size_t r = tree.runs_.size(); r-- > first_run;) {
    Source s;
    s.flags = tree.runs_[r].flags;
    WEAVER_RETURN_IF_ERROR(tree.runs_[r].tree->seek_cursor(from, &s.cursor));
    s.valid = s.cursor.valid();
    sources_.push_back(std::move(s));
  }
  return settle();
}

uint64_t LsmMergeIterator::source_key(const Source& s) const {
  return s.mem ? mem_->key_at(s.pos) : s.cursor.key();
}

Status LsmMergeIterator::advance(Source& s) {
  if (s.mem) {
    s.valid = ++s.pos < mem_->size();
    return Status::Ok();
  }
  WEAVER_RETURN_IF_ERROR(s.cursor.next());
  s.valid = s.cursor.valid();
  return Status::Ok();
}

bool LsmMergeIterator::tombstone() const {
  const Source& s = sources_[winner_];
  if (s.mem) return mem_->tombstone_at(s.pos);
  return s.flags && s.cursor.payload()[0] != std::byte{0};
}

const std::byte* LsmMergeIterator::payload() const {
  const Source& s = sources_[winner_];
  if (s.mem) return mem_->payload_at(s.pos);
  return s.cursor.payload() + (s.flags ? 1 : 0);
}

Status LsmMergeIterator::settle() {
  while (true) {
    winner_ = -1;
    for (size_t i = 0; i < sources_.size(); ++i) {
      if (!sources_[i].valid) continue;
      const uint64_t k = source_key(sources_[i]);
      if (winner_ < 0 || k < key_) {  // strictly less: the newer source keeps ties
        winner_ = static_cast<int>(i);
        key_ = k;
      }
    }
    if (winner_ < 0) return Status::Ok();
    for (size_t i = winner_ + 1; i < sources_.size(); ++i) {  // older entries of the key
      if (sources_[i].valid && source_key(sources_[i]) == key_) {
        if (on_shadow_ != nullptr && *on_shadow_) WEAVER_RETURN_IF_ERROR(report_shadow(i));
        WEAVER_RETURN_IF_ERROR(advance(sources_[i]));
      }
    }
    if (keep_tombstones_ || !tombstone()) return Status::Ok();
    WEAVER_RETURN_IF_ERROR(advance(sources_[winner_]));
  }
}

// The hook gets the winner's entry over source i's.
Status LsmMergeIterator::report_shadow(size_t i) {
  const int winner = winner_;
  const std::byte* newer = tombstone() ? nullptr : payload();
  winner_ = static_cast<int>(i);
  const std::byte* older = tombstone() ? nullptr : payload();
  winner_ = winner;
  return (*on_shadow_)(key_, newer, older);
}

Status LsmMergeIterator::next() {
  WEAVER_RETURN_IF_ERROR(advance(sources_[winner_]));
  return settle();
}

}  // namespace weaver
