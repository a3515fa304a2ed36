// Packed leaves: the encoder and the reader (format: storage/packed_leaf.h).
#include "storage/packed_leaf.h"

#include <algorithm>
#include <bit>
#include <cstring>

#include "schema/octant.h"
#include "storage/page_format.h"
#include "storage/page_search.h"

namespace weaver::page {
namespace {

constexpr size_t kPgBlocks = 16, kPgFields = 18, kPgCoding = 19, kFieldsStart = 20, kFieldBytes = 9;
constexpr uint8_t kCodingColumns = 0, kCodingDictionary = 1;
constexpr uint32_t kDictMinPayload = 4;
constexpr uint8_t kModeSuccessor = 0x80, kShiftMask = 0x3f;

uint64_t blocks_for(uint64_t n) { return (n + kPackedBlock - 1) / kPackedBlock; }
uint64_t bits_to_bytes(uint64_t bits) { return (bits + 7) / 8; }
uint64_t block_bytes(uint32_t count, uint32_t width) {
  return count <= 1 ? 0 : bits_to_bytes(uint64_t{count - 1} * width);
}

// The predicted next key of mode 1.  Defined for every u64 (damaged pages
// decode to garbage, never to undefined behaviour).
uint64_t successor(uint64_t key) { return octant_key_subtree_end_of_any(key); }

// A field's raw little-endian bytes as an integer.  Fixed-size loads: a
// memcpy of a run-time size is a library call, and this is on every append.
inline uint64_t load_field(const std::byte* p, uint32_t size) {
  switch (size) {
    case 1: return static_cast<uint64_t>(p[0]);
    case 2: return load16(p);
    case 4: return load32(p);
    default: return load64(p);
  }
}

// Bits [pos, pos + w) of the stream at `base`, w <= 64.  Reads up to 9 bytes
// from byte pos/8: the page's slack keeps that inside the page.
inline uint64_t read_bits(const std::byte* base, uint64_t pos, uint32_t w) {
  const std::byte* p = base + (pos >> 3);
  const uint32_t s = pos & 7;
  uint64_t v = load64(p) >> s;
  if (s + w > 64) v |= static_cast<uint64_t>(p[8]) << (64 - s);
  return w >= 64 ? v : v & ((uint64_t{1} << w) - 1);
}

// Writes values of given widths one after another from a byte boundary,
// through a 64-bit accumulator: one store per 64 bits instead of a load and
// a store per value.  finish() stores the last word whole: up to 7 bytes of
// zeros past the bits, which the next region overwrites or the page's
// slack absorbs.
class BitWriter {
 public:
  explicit BitWriter(std::byte* at) : p_(at) {}
  void put(uint64_t v, uint32_t w) {
    if (w == 0) return;
    if (w < 64) v &= (uint64_t{1} << w) - 1;
    acc_ |= v << used_;
    const uint32_t total = used_ + w;
    if (total < 64) {
      used_ = total;
      return;
    }
    store64(p_, acc_);
    p_ += 8;
    used_ = total - 64;
    acc_ = used_ == 0 ? 0 : v >> (w - used_);
  }
  void finish() {
    if (used_ > 0) store64(p_, acc_);
  }

 private:
  std::byte* p_;
  uint64_t acc_ = 0;
  uint32_t used_ = 0;
};

// Decodes n values of a column (frame `min`, `w` bits each) into the field
// of n rows `stride` bytes apart.  T is the field's width; a fixed-size
// store and a shift-and-mask per value keep this close to a memcpy.
template <typename T>
void decode_column(const std::byte* col, uint32_t w, uint64_t min, uint32_t n, std::byte* out,
                   uint32_t stride) {
  if (w == 0) {
    const auto v = static_cast<T>(min);
    for (uint32_t i = 0; i < n; ++i, out += stride) std::memcpy(out, &v, sizeof v);
    return;
  }
  uint64_t pos = 0;
  if (w <= 56) {  // one unaligned load holds every value
    const uint64_t mask = (uint64_t{1} << w) - 1;
    for (uint32_t i = 0; i < n; ++i, out += stride, pos += w) {
      const auto v = static_cast<T>(min + ((load64(col + (pos >> 3)) >> (pos & 7)) & mask));
      std::memcpy(out, &v, sizeof v);
    }
    return;
  }
  for (uint32_t i = 0; i < n; ++i, out += stride, pos += w) {
    const auto v = static_cast<T>(min + read_bits(col, pos, w));
    std::memcpy(out, &v, sizeof v);
  }
}

// A hash of a payload row of `size` bytes.
inline uint64_t row_hash(const std::byte* p, uint32_t size) {
  uint64_t h = size;
  for (uint32_t at = 0; at < size; at += 8) {
    uint64_t v = 0;
    std::memcpy(&v, p + at, std::min<uint32_t>(8, size - at));
    h = (h ^ v) * 0x9E3779B97F4A7C15ULL;
    h ^= h >> 29;
  }
  return h;
}

// Whether two payload rows of `size` bytes are equal.  The common row
// sizes compare as fixed-size words, inline: a call to memcmp for each
// 12-byte material row was a few percent of construct.
inline bool rows_equal(const std::byte* a, const std::byte* b, uint32_t size) {
  switch (size) {
    case 12: return std::memcmp(a, b, 12) == 0;
    case 20: return std::memcmp(a, b, 20) == 0;
    default: return std::memcmp(a, b, size) == 0;
  }
}

}  // namespace

uint64_t PackedShape::index_bytes(uint64_t entries) const {
  return kFieldsStart + kFieldBytes * field_sizes.size() + 12 * blocks_for(entries);
}

PackedShape PackedShape::of(uint32_t page_size, KeyKind kind, const RecordSchema& schema) {
  PackedShape s;
  s.page_size = page_size;
  s.key_kind = kind;
  for (const Field& f : schema.fields()) s.field_sizes.push_back(field_type_size(f.type));
  s.payload = schema.record_size();
  return s;
}

// ---------------------------------------------------------------------------
// Builder.
// ---------------------------------------------------------------------------

PackedLeafBuilder::PackedLeafBuilder(const PackedShape& shape)
    : shape_(shape), cols_(shape.field_sizes.size()), scratch_cols_(shape.field_sizes.size()) {
  // A dictionary of more rows than a page holds raw cannot fit: that many
  // is all it needs to tell apart.  Payloads narrower than kDictMinPayload
  // (a node's kind) stay column-wise: a frame of reference is as small.
  if (shape.payload >= kDictMinPayload) {
    dict_max_rows_ = shape.page_size / shape.payload;
    dict_slots_.resize(std::bit_ceil(2 * dict_max_rows_ + 2));
  }
  dict_over_ = shape.payload < kDictMinPayload;
}

void PackedLeafBuilder::clear() {
  keys_.clear();
  vals_.clear();
  closed_.clear();
  key_bytes_closed_ = 0;
  open_ = OpenBlock{};
  std::fill(cols_.begin(), cols_.end(), Column{});
  std::fill(dict_slots_.begin(), dict_slots_.end(), DictSlot{});
  dict_first_.clear();
  dict_over_ = shape_.payload < kDictMinPayload;
}

size_t PackedLeafBuilder::dict_probe(const std::byte* row, const std::byte* group) const {
  const size_t mask = dict_slots_.size() - 1, have = keys_.size();
  const uint32_t size = shape_.payload;
  for (size_t s = row_hash(row, size) & mask;; s = (s + 1) & mask) {
    const uint32_t first = dict_slots_[s].first;
    if (first == UINT32_MAX) return s;
    const std::byte* at =
        first < have ? vals_.data() + size_t{first} * size : group + size_t{first - have} * size;
    if (rows_equal(at, row, size)) return s;
  }
}

bool PackedLeafBuilder::dict_add(const std::byte* vals, uint32_t count) {
  dict_added_.clear();
  if (dict_over_) return false;
  const uint32_t size = shape_.payload;
  // Rows come in runs (a mesh's neighbours share their material): a row
  // equal to the one before is in the dictionary already.
  const std::byte* prev = keys_.empty() ? nullptr : vals_.data() + vals_.size() - size;
  for (uint32_t i = 0; i < count; ++i) {
    const std::byte* row = vals + size_t{i} * size;
    if (prev != nullptr && rows_equal(prev, row, size)) continue;
    prev = row;
    const size_t s = dict_probe(row, vals);
    if (dict_slots_[s].first != UINT32_MAX) continue;
    if (dict_first_.size() == dict_max_rows_) return false;
    const auto entry = static_cast<uint32_t>(keys_.size() + i);
    dict_slots_[s] = {entry, static_cast<uint32_t>(dict_first_.size())};
    dict_first_.push_back(entry);
    dict_added_.push_back(s);
  }
  return true;
}

// Linear probing: the slots filled last end their chains, so emptying them
// in reverse leaves every other chain whole.
void PackedLeafBuilder::dict_rollback() {
  for (auto it = dict_added_.rbegin(); it != dict_added_.rend(); ++it) {
    dict_slots_[*it] = DictSlot{};
    dict_first_.pop_back();
  }
  dict_added_.clear();
}

inline void PackedLeafBuilder::extend(OpenBlock& b, uint64_t key, KeyKind kind) {
  if (b.count == 0) {
    b.base = b.prev = key;
    b.count = 1;
    return;
  }
  const uint64_t d = key - b.prev;
  b.shift = std::min(b.shift, std::countr_zero(d));
  b.max_delta = std::max(b.max_delta, d);
  if (kind == KeyKind::kOctant && b.successor_ok) {
    const uint64_t e = successor(b.prev);
    if (e == UINT64_MAX || key < e) {
      b.successor_ok = false;
    } else {
      b.max_residual = std::max(b.max_residual, key - e);
    }
  }
  b.prev = key;
  ++b.count;
}

PackedLeafBuilder::BlockCode PackedLeafBuilder::choose(const OpenBlock& b, KeyKind kind) {
  if (b.count <= 1) return {0, 0};
  const BlockCode delta{static_cast<uint8_t>(std::bit_width((b.max_delta >> b.shift) - 1)),
                        static_cast<uint8_t>(b.shift)};
  if (kind != KeyKind::kOctant || !b.successor_ok) return delta;
  const auto w = static_cast<uint8_t>(std::bit_width(b.max_residual));
  return w < delta.width ? BlockCode{w, kModeSuccessor} : delta;
}

uint64_t PackedLeafBuilder::column_bytes(size_t n, const std::vector<Column>& cols) const {
  uint64_t bytes = 0;
  for (const Column& c : cols) bytes += bits_to_bytes(n * uint64_t(std::bit_width(c.max - c.min)));
  return bytes;
}

uint64_t PackedLeafBuilder::dictionary_bytes(size_t n, size_t dict_rows) const {
  if (dict_over_ || dict_rows == 0) return UINT64_MAX;
  const auto w = static_cast<uint64_t>(std::bit_width(dict_rows - 1));
  return bits_to_bytes(n * w) + uint64_t{dict_rows} * shape_.payload;
}

uint64_t PackedLeafBuilder::bytes_for(size_t n, uint64_t key_bytes_closed, const OpenBlock& open,
                                      const std::vector<Column>& cols, size_t dict_rows) const {
  const uint64_t bytes =
      kFieldsStart + kFieldBytes * cols.size() + 12 * blocks_for(n) + key_bytes_closed +
      block_bytes(open.count, choose(open, shape_.key_kind).width) + kPackedSlack;
  return bytes + std::min(column_bytes(n, cols), dictionary_bytes(n, dict_rows));
}

bool PackedLeafBuilder::add(uint64_t key, const std::byte* payload) {
  return add_group(&key, payload, 1);
}

// A page's size only grows as entries are added (widths only widen), so if
// a group fits, so does each of its prefixes: checking once per group ends
// the page where adding one at a time would.
bool PackedLeafBuilder::add_group(const uint64_t* keys, const std::byte* vals, uint32_t count) {
  const size_t n = keys_.size() + count;
  if (n > kPackedMaxEntries) return false;
  const size_t closed_before = closed_.size();
  uint64_t closed_bytes = key_bytes_closed_;
  OpenBlock open = open_;
  scratch_cols_ = cols_;
  for (uint32_t i = 0; i < count; ++i) {
    if (open.count == kPackedBlock) {
      closed_.push_back(choose(open, shape_.key_kind));
      closed_bytes += block_bytes(open.count, closed_.back().width);
      open = OpenBlock{};
    }
    extend(open, keys[i], shape_.key_kind);
    const std::byte* field = vals + size_t{i} * shape_.payload;
    for (size_t f = 0; f < cols_.size(); ++f) {
      const uint64_t v = load_field(field, shape_.field_sizes[f]);
      scratch_cols_[f] = {std::min(scratch_cols_[f].min, v), std::max(scratch_cols_[f].max, v)};
      field += shape_.field_sizes[f];
    }
  }
  // Past the dictionary's room the page is column-wise from here on: it
  // stops counting rows (and a dictionary can never come back).  A group
  // that does not fit leaves the dictionary as it was: the entries before
  // it may need it to fit.
  const bool over_before = dict_over_;
  if (!dict_add(vals, count)) {
    dict_rollback();
    dict_over_ = true;
  }
  if (bytes_for(n, closed_bytes, open, scratch_cols_, dict_first_.size()) > shape_.page_size) {
    closed_.resize(closed_before);
    dict_rollback();
    dict_over_ = over_before;
    return false;
  }
  key_bytes_closed_ = closed_bytes;
  open_ = open;
  cols_.swap(scratch_cols_);
  keys_.insert(keys_.end(), keys, keys + count);
  vals_.insert(vals_.end(), vals, vals + size_t{count} * shape_.payload);
  return true;
}

uint32_t PackedLeafBuilder::add_range(const uint64_t* keys, const std::byte* vals, uint32_t from,
                                      uint32_t to) {
  constexpr uint32_t kGroup = 16;
  uint32_t i = from;
  while (to - i >= kGroup && add_group(keys + i, vals + size_t{i} * shape_.payload, kGroup)) {
    i += kGroup;
  }
  while (i < to && add(keys[i], vals + size_t{i} * shape_.payload)) ++i;
  return i;
}

void PackedLeafBuilder::encode(std::byte* pg) const {
  const auto n = static_cast<uint32_t>(keys_.size());
  const auto m = static_cast<uint32_t>(blocks_for(n));
  const size_t nf = cols_.size();
  std::memset(pg + kPageHeaderBytes, 0, shape_.page_size - kPageHeaderBytes);
  pg[kPgType] = static_cast<std::byte>(PageType::kPackedLeaf);
  set_count(pg, n);
  store16(pg + kPgBlocks, static_cast<uint16_t>(m));
  pg[kPgFields] = static_cast<std::byte>(nf);
  std::byte* bases = pg + kFieldsStart + kFieldBytes * nf;
  std::byte* blocks = bases + 8 * size_t{m};
  std::byte* key_bits = blocks + 4 * size_t{m};
  uint64_t off = 0;  // bytes into the key bits
  for (uint32_t j = 0; j < m; ++j) {
    const uint32_t first = j * kPackedBlock, cnt = std::min(kPackedBlock, n - first);
    const BlockCode code = j < closed_.size() ? closed_[j] : choose(open_, shape_.key_kind);
    store64(bases + 8 * size_t{j}, keys_[first]);
    store16(blocks + 4 * size_t{j}, static_cast<uint16_t>(off));
    blocks[4 * size_t{j} + 2] = static_cast<std::byte>(code.width);
    blocks[4 * size_t{j} + 3] = static_cast<std::byte>(code.mode);
    const int shift = code.mode & kShiftMask;
    BitWriter bits(key_bits + off);
    for (uint32_t i = 1; i < cnt; ++i) {
      const uint64_t prev = keys_[first + i - 1], k = keys_[first + i];
      const uint64_t r =
          (code.mode & kModeSuccessor) ? k - successor(prev) : ((k - prev) >> shift) - 1;
      bits.put(r, code.width);
    }
    bits.finish();
    off += block_bytes(cnt, code.width);
  }
  std::byte* col = key_bits + off;
  if (dictionary_bytes(n, dict_first_.size()) < column_bytes(n, cols_)) {
    encode_dictionary(pg, col);
    return;
  }
  size_t field_off = 0;
  for (size_t f = 0; f < nf; ++f) {
    const Column& c = cols_[f];
    const auto w = static_cast<uint32_t>(std::bit_width(c.max - c.min));
    store64(pg + kFieldsStart + kFieldBytes * f, c.min);
    pg[kFieldsStart + kFieldBytes * f + 8] = static_cast<std::byte>(w);
    BitWriter bits(col);
    for (uint32_t i = 0; i < n; ++i) {
      bits.put(load_field(payload(i) + field_off, shape_.field_sizes[f]) - c.min, w);
    }
    bits.finish();
    col += bits_to_bytes(uint64_t{n} * w);
    field_off += shape_.field_sizes[f];
  }
}

// Coding 1: the index of each entry's row, then the rows.
void PackedLeafBuilder::encode_dictionary(std::byte* pg, std::byte* col) const {
  const auto n = static_cast<uint32_t>(keys_.size());
  const uint64_t rows = dict_first_.size();
  const auto w = static_cast<uint32_t>(std::bit_width(rows - 1));
  pg[kPgCoding] = static_cast<std::byte>(kCodingDictionary);
  store64(pg + kFieldsStart, rows);
  pg[kFieldsStart + 8] = static_cast<std::byte>(w);
  BitWriter bits(col);
  uint32_t ordinal = 0;
  for (uint32_t i = 0; i < n; ++i) {
    if (i == 0 || !rows_equal(payload(i), payload(i - 1), shape_.payload)) {
      ordinal = dict_slots_[dict_probe(payload(i), nullptr)].ordinal;
    }
    bits.put(ordinal, w);
  }
  bits.finish();
  std::byte* out = col + bits_to_bytes(uint64_t{n} * w);
  for (uint32_t first : dict_first_) {
    std::memcpy(out, payload(first), shape_.payload);
    out += shape_.payload;
  }
}

// ---------------------------------------------------------------------------
// Reader.
// ---------------------------------------------------------------------------

bool PackedLeaf::open(const std::byte* pg, const PackedShape& shape) {
  pg_ = pg;
  shape_ = &shape;
  n_ = count(pg);
  m_ = load16(pg + kPgBlocks);
  const size_t nf = shape.field_sizes.size();
  if (static_cast<size_t>(pg[kPgFields]) != nf || m_ != blocks_for(n_)) return false;
  // Offsets are checked as integers before any pointer is formed from them.
  const size_t limit = shape.page_size - kPackedSlack;
  if (kFieldsStart + kFieldBytes * nf + 12 * size_t{m_} > limit) return false;
  end_ = pg + limit;
  fields_ = pg + kFieldsStart;
  bases_ = fields_ + kFieldBytes * nf;
  blocks_ = bases_ + 8 * size_t{m_};
  key_bits_ = blocks_ + 4 * size_t{m_};
  uint64_t col = static_cast<uint64_t>(key_bits_ - pg);
  if (m_ > 0) {
    const std::byte* last = blocks_ + 4 * size_t{m_ - 1};
    const uint32_t cnt = n_ - (m_ - 1) * kPackedBlock;
    col += load16(last) + block_bytes(cnt, static_cast<uint32_t>(last[2]));
  }
  const auto coding = static_cast<uint8_t>(pg[kPgCoding]);
  if (coding == kCodingDictionary) return open_dictionary(col, limit);
  if (coding != kCodingColumns) return false;
  dict_index_ = nullptr;
  cols_.resize(nf);
  for (size_t f = 0; f < nf; ++f) {
    const auto w = static_cast<uint32_t>(fields_[kFieldBytes * f + 8]);
    if (w > 8 * shape.field_sizes[f] || col > limit) return false;
    cols_[f] = pg + col;
    col += bits_to_bytes(uint64_t{n_} * w);
  }
  return col <= limit;
}

// Coding 1, its index column from byte `col` of the page.
bool PackedLeaf::open_dictionary(uint64_t col, uint64_t limit) {
  cols_.clear();
  if (shape_->field_sizes.empty()) return false;
  dict_count_ = load64(fields_);
  dict_width_ = static_cast<uint32_t>(fields_[8]);
  if (dict_count_ == 0 || dict_count_ > shape_->page_size ||
      dict_width_ != static_cast<uint32_t>(std::bit_width(dict_count_ - 1))) {
    return false;
  }
  dict_index_ = pg_ + col;
  col += bits_to_bytes(uint64_t{n_} * dict_width_);
  dict_rows_ = pg_ + col;
  col += dict_count_ * shape_->payload;
  return col <= limit;
}

// The dictionary row of entry i (a damaged page's index past the rows reads
// the last row: garbage, as any damaged value, never out of bounds).
const std::byte* PackedLeaf::dict_row(uint32_t i) const {
  const uint64_t r = read_bits(dict_index_, uint64_t{i} * dict_width_, dict_width_);
  return dict_rows_ + std::min(r, dict_count_ - 1) * shape_->payload;
}

// Every entry's row into vals (rows of `Size` bytes, or the shape's when 0).
template <uint32_t Size>
bool PackedLeaf::decode_dictionary(std::byte* vals) const {
  const uint32_t size = Size != 0 ? Size : shape_->payload, w = dict_width_;
  const uint64_t mask = w == 0 ? 0 : (uint64_t{1} << w) - 1;  // w <= 16: one load holds it
  uint64_t pos = 0;
  for (uint32_t i = 0; i < n_; ++i, pos += w, vals += size) {
    const uint64_t r = (load64(dict_index_ + (pos >> 3)) >> (pos & 7)) & mask;
    if (r >= dict_count_) return false;
    std::memcpy(vals, dict_rows_ + r * size, Size != 0 ? Size : size);
  }
  return true;
}

const std::byte* PackedLeaf::block_bits(uint32_t j, uint32_t* cnt, uint32_t* w,
                                        uint8_t* mode) const {
  *cnt = std::min(kPackedBlock, n_ - j * kPackedBlock);
  const std::byte* b = blocks_ + 4 * size_t{j};
  *w = static_cast<uint32_t>(b[2]);
  *mode = static_cast<uint8_t>(b[3]);
  const size_t off = load16(b);
  if (*w > 64 || off + block_bytes(*cnt, *w) > static_cast<size_t>(end_ - key_bits_)) {
    return nullptr;
  }
  return key_bits_ + off;
}

bool PackedLeaf::block_keys(uint32_t j, uint64_t* out, uint32_t* cnt_out) const {
  uint32_t cnt = 0, w = 0;
  uint8_t mode = 0;
  const std::byte* bits = block_bits(j, &cnt, &w, &mode);
  if (bits == nullptr) return false;
  uint64_t k = load64(bases_ + 8 * size_t{j});
  out[0] = k;
  if (mode & kModeSuccessor) {
    for (uint32_t i = 1; i < cnt; ++i) out[i] = k = successor(k) + read_bits(bits, (i - 1) * w, w);
  } else {
    const int shift = mode & kShiftMask;
    for (uint32_t i = 1; i < cnt; ++i) {
      out[i] = k = k + ((read_bits(bits, (i - 1) * w, w) + 1) << shift);
    }
  }
  *cnt_out = cnt;
  return true;
}

void PackedLeaf::prefetch_payloads(uint32_t j) const {
  const uint64_t cnt = std::min(kPackedBlock, n_ - j * kPackedBlock);
  if (dict_index_ != nullptr) {
    __builtin_prefetch(dict_index_ + uint64_t{j} * kPackedBlock * dict_width_ / 8);
    return;
  }
  for (size_t f = 0; f < cols_.size(); ++f) {
    const uint64_t w = static_cast<uint32_t>(fields_[kFieldBytes * f + 8]);
    const uint64_t first_bit = uint64_t{j} * kPackedBlock * w;
    const std::byte* from = cols_[f] + first_bit / 8;
    const uint64_t bytes = (first_bit % 8 + cnt * w + 7) / 8;
    for (uint64_t off = 0; off < bytes; off += 64) __builtin_prefetch(from + off);
    if (bytes > 0) __builtin_prefetch(from + bytes - 1);
  }
}

bool PackedLeaf::bound(uint64_t k, bool upper, uint32_t* pos, uint64_t* below, uint64_t* at,
                       bool payload_next) const {
  const uint32_t c = upper ? upper_bound(bases_, m_, k) : lower_bound(bases_, m_, k);
  if (c == 0) {
    *pos = 0;
    if (at != nullptr && m_ > 0) *at = load64(bases_);
    return true;
  }
  // The payload's line follows from the entry's place, found only once the
  // block is decoded: asking for the block's lines now overlaps the two
  // (10M random gets in the pool: 2.8M/s -> 3.2M/s).
  if (payload_next) prefetch_payloads(c - 1);
  // Decodes the block only as far as the answer: half of it on average.
  uint32_t cnt = 0, w = 0;
  uint8_t mode = 0;
  const std::byte* bits = block_bits(c - 1, &cnt, &w, &mode);
  if (bits == nullptr) return false;
  const int shift = mode & kShiftMask;
  uint64_t prev = load64(bases_ + 8 * size_t{c - 1});  // the base: < k (<= k when upper)
  uint64_t next = 0;
  uint32_t i = 1;
  for (; i < cnt; ++i, prev = next) {
    const uint64_t r = read_bits(bits, uint64_t{i - 1} * w, w);
    next = (mode & kModeSuccessor) ? successor(prev) + r : prev + ((r + 1) << shift);
    if (upper ? next > k : next >= k) break;
  }
  *pos = (c - 1) * kPackedBlock + i;
  if (below != nullptr) *below = prev;
  if (at != nullptr && *pos < n_) *at = i < cnt ? next : load64(bases_ + 8 * size_t{c});
  return true;
}

bool PackedLeaf::key(uint32_t i, uint64_t* out) const {
  uint64_t keys[kPackedBlock];
  uint32_t cnt = 0;
  if (!block_keys(i / kPackedBlock, keys, &cnt)) return false;
  *out = keys[i % kPackedBlock];
  return true;
}

void PackedLeaf::payload(uint32_t i, std::byte* out) const {
  if (dict_index_ != nullptr) {
    std::memcpy(out, dict_row(i), shape_->payload);
    return;
  }
  for (size_t f = 0; f < cols_.size(); ++f) {
    const uint32_t w = static_cast<uint32_t>(fields_[kFieldBytes * f + 8]);
    const uint64_t v = load64(fields_ + kFieldBytes * f) + read_bits(cols_[f], uint64_t{i} * w, w);
    std::memcpy(out, &v, shape_->field_sizes[f]);
    out += shape_->field_sizes[f];
  }
}

bool PackedLeaf::decode(uint64_t* keys, std::byte* vals) const {
  uint32_t cnt = 0;
  for (uint32_t j = 0; j < m_; ++j) {
    if (!block_keys(j, keys + size_t{j} * kPackedBlock, &cnt)) return false;
  }
  if (vals == nullptr) return true;
  const uint32_t stride = shape_->payload;
  if (dict_index_ != nullptr) {
    switch (stride) {  // a copy of a known size is a few moves, not a call
      case 12: return decode_dictionary<12>(vals);
      case 20: return decode_dictionary<20>(vals);
      default: return decode_dictionary<0>(vals);
    }
  }
  size_t field_off = 0;
  for (size_t f = 0; f < cols_.size(); ++f) {
    const uint32_t w = static_cast<uint32_t>(fields_[kFieldBytes * f + 8]);
    const uint64_t min = load64(fields_ + kFieldBytes * f);
    const uint32_t size = shape_->field_sizes[f];
    std::byte* out = vals + field_off;
    switch (size) {
      case 1: decode_column<uint8_t>(cols_[f], w, min, n_, out, stride); break;
      case 2: decode_column<uint16_t>(cols_[f], w, min, n_, out, stride); break;
      case 4: decode_column<uint32_t>(cols_[f], w, min, n_, out, stride); break;
      default: decode_column<uint64_t>(cols_[f], w, min, n_, out, stride); break;
    }
    field_off += size;
  }
  return true;
}

}  // namespace weaver::page
