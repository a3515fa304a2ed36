#include "storage/lsm.h"

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <limits>
#include <sstream>

#include "storage/lsm_merge.h"
#include "storage/manifest_file.h"

namespace weaver {
namespace {

namespace fs = std::filesystem;

constexpr char kRunList[] = "LSM";
constexpr char kRunListHeader[] = "weaver-lsm 1";  // do not change: on disk
constexpr char kTombstoneField[] = "lsm_tombstone";
constexpr int kFanIn = 4;
constexpr int kCompactedTier = 1 << 20;  // never merged by the tier rule
constexpr size_t kBatch = 4096;

// The run schema: the tombstone byte, then the table's fields.
RecordSchema with_tombstone(const RecordSchema& table) {
  RecordSchema s;
  std::string error;
  s.add_field(kTombstoneField, FieldType::kU8, &error);
  for (const Field& f : table.fields()) s.add_field(f.name, f.type, &error);
  return s;
}

RecordSchema without_tombstone(const RecordSchema& run) {
  RecordSchema s;
  std::string error;
  for (const Field& f : run.fields()) {
    if (f.name != kTombstoneField) s.add_field(f.name, f.type, &error);
  }
  return s;
}

uint64_t run_number(const std::string& file) {  // "run-12.bt" -> 12
  try {
    return std::stoull(file.substr(4));
  } catch (...) {
    return 0;
  }
}

}  // namespace

LsmTree::LsmTree(std::string dir, const LsmOptions& o)
    : dir_(std::move(dir)),
      o_(o),
      payload_(o.table.schema.record_size()),
      mem_(payload_, o.memtable_bytes) {
  scratch_.resize(payload_ + 1);
  floor_candidate_.resize(payload_ + 1);
}

LsmTree::~LsmTree() = default;

Status LsmTree::create(const std::string& dir, const LsmOptions& options,
                       std::unique_ptr<LsmTree>* out) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) return Status::IOError("cannot create " + dir + ": " + ec.message());
  if (fs::exists(dir + "/" + kRunList)) {
    return Status::InvalidArgument(dir + ": already holds an LSM store");
  }
  out->reset(new LsmTree(dir, options));
  return Status::Ok();
}

Status LsmTree::open(const std::string& dir, const LsmOptions& options,
                     std::unique_ptr<LsmTree>* out) {
  const std::string path = dir + "/" + kRunList;
  std::vector<std::string> lines;
  WEAVER_RETURN_IF_ERROR(read_manifest_file(path, kRunListHeader, &lines));
  std::unique_ptr<LsmTree> t(new LsmTree(dir, options));
  bool exact = false;
  for (const std::string& line : lines) {
    std::istringstream in(line);
    std::string kind, file;
    Run run;
    in >> kind;
    if (kind == "size") {
      in >> t->size_ >> exact;
    } else if (kind == "run" && (in >> file >> run.flags >> run.tier)) {
      std::unique_ptr<File> f;
      WEAVER_RETURN_IF_ERROR(open_posix_file(dir + "/" + file, OpenMode::kReadWrite, &f));
      WEAVER_RETURN_IF_ERROR(BTree::open(std::move(f), options.run_pool_bytes, &run.tree));
      run.file = file;
      t->next_file_ = std::max(t->next_file_, run_number(file) + 1);
      t->committed_.push_back(file);
      t->runs_.push_back(std::move(run));
    } else {
      return Status::Corruption(path + ": bad line '" + line + "'");
    }
  }
  t->size_exact_ = exact;
  if (!t->runs_.empty()) {  // the table options, from a run
    t->o_.table = t->runs_.back().tree->options();
    t->o_.table.schema = without_tombstone(t->o_.table.schema);
    t->payload_ = t->o_.table.schema.record_size();
    t->mem_ = Memtable(t->payload_, options.memtable_bytes);
    t->scratch_.resize(t->payload_ + 1);
    t->floor_candidate_.resize(t->payload_ + 1);
  }
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {  // runs of no commit
    const std::string name = entry.path().filename().string();
    bool live = false;
    for (const Run& r : t->runs_) live = live || r.file == name;
    if (!live && (name.rfind("run-", 0) == 0 || name == std::string(kRunList) + ".tmp")) {
      fs::remove(entry.path(), ec);
    }
  }
  uint64_t max_key = 0;
  bool found = false;
  size_t skip = 0;
  WEAVER_RETURN_IF_ERROR(
      t->live_floor(std::numeric_limits<uint64_t>::max(), &max_key, &found, &skip));
  t->has_max_ = found;
  t->max_key_ = max_key;
  *out = std::move(t);
  return Status::Ok();
}

Status LsmTree::new_run_file(bool flags, std::unique_ptr<BTree>* tree, std::string* file) {
  *file = "run-" + std::to_string(next_file_++) + ".bt";
  TableOptions t = o_.table;
  if (flags) t.schema = with_tombstone(t.schema);
  std::unique_ptr<File> f;
  WEAVER_RETURN_IF_ERROR(open_posix_file(dir_ + "/" + *file, OpenMode::kCreateTruncate, &f));
  return BTree::create(std::move(f), t, o_.run_pool_bytes, tree);
}

Status LsmTree::write_merged(LsmMergeIterator& it, BTree& out, bool flags, uint64_t* written) {
  const size_t rec = payload_ + (flags ? 1 : 0);
  std::vector<uint64_t> keys;
  std::vector<std::byte> payloads;
  keys.reserve(kBatch);
  payloads.reserve(kBatch * rec);
  *written = 0;
  auto flush_batch = [&]() -> Status {
    WEAVER_RETURN_IF_ERROR(out.append_batch(keys.data(), payloads.data(), keys.size()));
    *written += keys.size();
    keys.clear();
    payloads.clear();
    return Status::Ok();
  };
  while (it.valid()) {
    keys.push_back(it.key());
    if (flags) payloads.push_back(std::byte{static_cast<uint8_t>(it.tombstone() ? 1 : 0)});
    payloads.insert(payloads.end(), it.payload(), it.payload() + payload_);
    if (keys.size() == kBatch) WEAVER_RETURN_IF_ERROR(flush_batch());
    WEAVER_RETURN_IF_ERROR(it.next());
  }
  return flush_batch();
}

Status LsmTree::make_iterator(uint64_t from, bool keep_tombstones,
                              std::unique_ptr<LsmMergeIterator>* it) {
  mem_.sort();
  *it = std::make_unique<LsmMergeIterator>();
  return (*it)->init(*this, 0, true, from, keep_tombstones);
}

Status LsmTree::merge_tail(size_t first, bool with_memtable) {
  const bool bottom = first == 0;  // nothing older: tombstones can go
  bool flags = false;
  int tier = with_memtable ? 0 : runs_[first].tier + 1;
  for (size_t r = first; r < runs_.size(); ++r) flags = flags || runs_[r].flags;
  flags = !bottom && (flags || (with_memtable && mem_.tombstones() > 0));
  if (with_memtable) mem_.sort();
  LsmMergeIterator it;
  WEAVER_RETURN_IF_ERROR(it.init(*this, first, with_memtable, 0, !bottom));
  Run run;
  WEAVER_RETURN_IF_ERROR(new_run_file(flags, &run.tree, &run.file));
  uint64_t written = 0;
  WEAVER_RETURN_IF_ERROR(write_merged(it, *run.tree, flags, &written));
  run.flags = flags;
  run.tier = tier;
  ++runs_written_;
  records_written_ += written;
  for (size_t r = first; r < runs_.size(); ++r) {
    runs_[r].tree.reset();
    retire(runs_[r].file);
  }
  runs_.resize(first);
  if (with_memtable) mem_.clear();
  if (written > 0) {
    runs_.push_back(std::move(run));
  } else {
    run.tree.reset();
    retire(run.file);
  }
  if (bottom && mem_.empty()) {
    size_ = written;
    size_exact_ = true;
  }
  return Status::Ok();
}

Status LsmTree::maybe_merge() {
  while (runs_.size() >= kFanIn) {
    const size_t first = runs_.size() - kFanIn;
    const int tier = runs_[first].tier;
    if (tier == kCompactedTier) return Status::Ok();
    for (size_t r = first + 1; r < runs_.size(); ++r) {
      if (runs_[r].tier != tier) return Status::Ok();
    }
    WEAVER_RETURN_IF_ERROR(merge_tail(first, false));
  }
  return Status::Ok();
}

Status LsmTree::flush() {
  if (mem_.empty()) return Status::Ok();
  WEAVER_RETURN_IF_ERROR(merge_tail(runs_.size(), true));
  return maybe_merge();
}

Status LsmTree::put(uint64_t key, const std::byte* payload, bool* replaced) {
  const std::byte* old = nullptr;
  bool dead = false;
  const bool in_memtable = mem_.find(key, &old, &dead);
  if (in_memtable && o_.on_shadow) {
    WEAVER_RETURN_IF_ERROR(o_.on_shadow(key, payload, dead ? nullptr : old));
  }
  if (replaced != nullptr) {
    bool found = !dead;
    if (!in_memtable) WEAVER_RETURN_IF_ERROR(get(key, nullptr, &found));
    *replaced = found;
    if (!found) ++size_;
  } else if (in_memtable) {
    if (dead) ++size_;  // a tombstone hid every older entry
  } else {
    ++size_;  // an upper bound unless nothing older can hold the key
    if (!runs_.empty()) size_exact_ = false;
  }
  mem_.put(key, payload);
  if (!has_max_ || key > max_key_) max_key_ = key;
  has_max_ = true;
  if (mem_.memory_bytes() >= o_.memtable_bytes) return flush();
  return Status::Ok();
}

Status LsmTree::append(uint64_t key, const std::byte* payload) {
  if (has_max_ && key <= max_key_) {
    uint64_t last = 0;
    bool found = false;
    size_t skip = 0;
    WEAVER_RETURN_IF_ERROR(live_floor(std::numeric_limits<uint64_t>::max(), &last, &found, &skip));
    if (found && key <= last) {
      return Status::InvalidArgument(dir_ + ": append out of order: key " + std::to_string(key) +
                                     " after key " + std::to_string(last));
    }
  }
  ++size_;
  mem_.put(key, payload);
  has_max_ = true;
  max_key_ = std::max(max_key_, key);
  if (mem_.memory_bytes() >= o_.memtable_bytes) return flush();
  return Status::Ok();
}

Status LsmTree::erase(uint64_t key) {
  bool found = false;
  WEAVER_RETURN_IF_ERROR(get(key, nullptr, &found));
  if (!found) return Status::NotFound(dir_ + ": no key " + std::to_string(key));
  mem_.erase(key);
  --size_;
  if (mem_.memory_bytes() >= o_.memtable_bytes) return flush();
  return Status::Ok();
}

Status LsmTree::get(uint64_t key, std::byte* payload_out, bool* found) {
  if (BTree* t = compacted_run()) return t->get(key, payload_out, found);
  const std::byte* p = nullptr;
  bool dead = false;
  *found = false;
  if (mem_.find(key, &p, &dead)) {
    *found = !dead;
    if (*found && payload_out != nullptr) std::memcpy(payload_out, p, payload_);
    return Status::Ok();
  }
  for (size_t r = runs_.size(); r-- > 0;) {
    bool in_run = false;
    WEAVER_RETURN_IF_ERROR(runs_[r].tree->get(key, scratch_.data(), &in_run));
    if (!in_run) continue;
    const size_t skip = runs_[r].flags ? 1 : 0;
    *found = skip == 0 || scratch_[0] == std::byte{0};
    if (*found && payload_out != nullptr)
      std::memcpy(payload_out, scratch_.data() + skip, payload_);
    return Status::Ok();
  }
  return Status::Ok();
}

// The largest key <= key over all sources whose newest entry is live, and
// its payload (into scratch_, after `*skip` flag bytes).  Sources are asked
// newest first and a key found again in an older source does not displace
// it, so the winner holds the newest entry of its key.
Status LsmTree::live_floor(uint64_t key, uint64_t* key_out, bool* found, size_t* skip) {
  mem_.sort();
  std::vector<std::byte>& candidate = floor_candidate_;  // kept: floor is a hot path
  while (true) {
    *found = false;
    bool live = false;
    uint64_t best = 0;
    const size_t pos =
        key == std::numeric_limits<uint64_t>::max() ? mem_.size() : mem_.lower_bound(key + 1);
    if (pos > 0) {
      best = mem_.key_at(pos - 1);
      *found = true;
      live = !mem_.tombstone_at(pos - 1);
      *skip = 0;
      std::memcpy(scratch_.data(), mem_.payload_at(pos - 1), payload_);
    }
    for (size_t r = runs_.size(); r-- > 0;) {
      uint64_t k = 0;
      bool in_run = false;
      WEAVER_RETURN_IF_ERROR(runs_[r].tree->floor(key, &k, candidate.data(), &in_run));
      if (in_run && (!*found || k > best)) {
        best = k;
        *found = true;
        *skip = runs_[r].flags ? 1 : 0;
        live = *skip == 0 || candidate[0] == std::byte{0};
        scratch_.swap(candidate);
      }
    }
    if (!*found || live) {
      *key_out = best;
      return Status::Ok();
    }
    if (best == 0) {
      *found = false;
      return Status::Ok();
    }
    key = best - 1;
  }
}

Status LsmTree::floor(uint64_t key, uint64_t* key_out, std::byte* payload_out, bool* found) {
  if (BTree* t = compacted_run()) return t->floor(key, key_out, payload_out, found);
  size_t skip = 0;
  uint64_t k = 0;
  WEAVER_RETURN_IF_ERROR(live_floor(key, &k, found, &skip));
  if (!*found) return Status::Ok();
  if (key_out != nullptr) *key_out = k;
  if (payload_out != nullptr) std::memcpy(payload_out, scratch_.data() + skip, payload_);
  return Status::Ok();
}

Status LsmTree::seek(uint64_t key, std::unique_ptr<Cursor>* out) {
  if (BTree* t = compacted_run()) return t->seek(key, out);
  std::unique_ptr<LsmMergeIterator> it;
  WEAVER_RETURN_IF_ERROR(make_iterator(key, false, &it));
  *out = std::make_unique<LsmCursor>(std::move(it));
  return Status::Ok();
}

BTree* LsmTree::compacted_run() {
  if (!mem_.empty() || runs_.size() != 1 || runs_[0].flags) return nullptr;
  return runs_[0].tree.get();
}

Status LsmTree::rank(uint64_t key, uint64_t* out) {
  if (runs_.empty() && mem_.empty()) return *out = 0, Status::Ok();
  if (BTree* t = compacted_run()) return t->rank(key, out);
  std::unique_ptr<LsmMergeIterator> it;
  WEAVER_RETURN_IF_ERROR(make_iterator(0, false, &it));
  for (*out = 0; it->valid() && it->key() < key; ++*out) WEAVER_RETURN_IF_ERROR(it->next());
  return Status::Ok();
}

Status LsmTree::select(uint64_t index, uint64_t* key_out, std::byte* payload_out) {
  if (BTree* t = compacted_run()) return t->select(index, key_out, payload_out);
  std::unique_ptr<LsmMergeIterator> it;
  WEAVER_RETURN_IF_ERROR(make_iterator(0, false, &it));
  for (uint64_t i = 0; i < index && it->valid(); ++i) WEAVER_RETURN_IF_ERROR(it->next());
  if (!it->valid()) {
    return Status::InvalidArgument(dir_ + ": select " + std::to_string(index) + " past the end");
  }
  *key_out = it->key();
  if (payload_out != nullptr) std::memcpy(payload_out, it->payload(), payload_);
  return Status::Ok();
}

Status LsmTree::count(uint64_t* out) {
  if (!size_exact_) {
    std::unique_ptr<LsmMergeIterator> it;
    WEAVER_RETURN_IF_ERROR(make_iterator(0, false, &it));
    uint64_t n = 0;
    for (; it->valid(); ++n) WEAVER_RETURN_IF_ERROR(it->next());
    size_ = n;
    size_exact_ = true;
  }
  *out = size_;
  return Status::Ok();
}

Status LsmTree::compact() {
  if (compacted_run() != nullptr || (runs_.empty() && mem_.empty())) return Status::Ok();
  WEAVER_RETURN_IF_ERROR(merge_tail(0, true));
  if (!runs_.empty()) runs_.back().tier = kCompactedTier;
  return Status::Ok();
}

Status LsmTree::compact_into(BTree& out) {
  std::unique_ptr<LsmMergeIterator> it;
  WEAVER_RETURN_IF_ERROR(make_iterator(0, false, &it));
  uint64_t written = 0;
  return write_merged(*it, out, false, &written);
}

Status LsmTree::write_run_list() {
  std::vector<std::string> lines;
  lines.push_back("size " + std::to_string(size_) + " " + (size_exact_ ? "1" : "0"));
  for (const Run& r : runs_) {
    lines.push_back("run " + r.file + " " + (r.flags ? "1" : "0") + " " + std::to_string(r.tier));
  }
  return write_manifest_file(dir_, kRunList, kRunListHeader, lines);
}

Status LsmTree::commit() {
  WEAVER_RETURN_IF_ERROR(flush());
  for (Run& r : runs_) WEAVER_RETURN_IF_ERROR(r.tree->commit());
  WEAVER_RETURN_IF_ERROR(write_run_list());
  committed_.clear();
  for (const Run& r : runs_) committed_.push_back(r.file);
  std::error_code ec;
  for (const std::string& file : obsolete_) fs::remove(dir_ + "/" + file, ec);
  obsolete_.clear();
  return Status::Ok();
}

// A run merged away: its file goes now unless the committed run list still
// names it (a crash before the next commit reopens that list).
void LsmTree::retire(const std::string& file) {
  if (std::find(committed_.begin(), committed_.end(), file) != committed_.end()) {
    obsolete_.push_back(file);
    return;
  }
  std::error_code ec;
  fs::remove(dir_ + "/" + file, ec);
}

uint64_t LsmTree::file_bytes() const {
  uint64_t n = 0;
  for (const Run& r : runs_) n += r.tree->file_bytes();
  return n;
}

}  // namespace weaver
