// Packed leaves: the encoder (PackedLeafBuilder), keys in blocks and
// payloads column-wise; the row dictionary's half is in
// packed_row_dictionary.cc (format: storage/packed_leaf.h).
#include <algorithm>
#include <bit>
#include <cstring>

#include "storage/packed_bits.h"
#include "storage/packed_leaf.h"
#include "storage/page_format.h"

namespace weaver::page {
using namespace packed;

uint64_t PackedShape::index_bytes(uint64_t entries) const {
  return kFieldsStart + kFieldBytes * field_sizes.size() + 12 * blocks_for(entries);
}

PackedShape PackedShape::of(uint32_t page_size, KeyKind kind, const RecordSchema& schema) {
  PackedShape s;
  s.page_size = page_size;
  s.key_kind = kind;
  for (const Field& f : schema.fields()) s.field_sizes.push_back(field_type_size(f.type));
  s.payload = schema.record_size();
  s.uniform_field = s.field_sizes.empty() ? 0 : s.field_sizes[0];
  for (uint32_t size : s.field_sizes) {
    if (size != s.uniform_field) s.uniform_field = 0;
  }
  return s;
}

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
  dict_ordinal_.clear();
  dict_over_ = shape_.payload < kDictMinPayload;
}

// The block's figures over keys[0, count), all in the block: kept in
// locals across the run, not in the OpenBlock between keys (a store and a
// load a figure a key was most of add_group's time).  The deltas' common
// trailing zeros are those of their OR.  Past the first key that breaks
// the successor model, max_residual is never read (choose).
void PackedLeafBuilder::extend(OpenBlock& b, const uint64_t* keys, uint32_t count, KeyKind kind) {
  if (count == 0) return;
  uint32_t i = 0;
  if (b.count == 0) b.base = b.prev = keys[i++], b.count = 1;
  uint64_t prev = b.prev, any = 0, most = b.max_delta;
  for (uint32_t j = i; j < count; ++j) {
    const uint64_t d = keys[j] - prev;
    any |= d;
    most = std::max(most, d);
    prev = keys[j];
  }
  if (kind == KeyKind::kOctant && b.successor_ok) {
    bool ok = true;
    uint64_t residual = b.max_residual;
    prev = b.prev;
    for (uint32_t j = i; j < count; ++j) {
      // successor(prev), from its slot's step (kSuccessorStep); a step that
      // does not move past prev (the root's, or one past the root's end)
      // is successor()'s UINT64_MAX.
      const uint64_t high = prev & ~uint64_t{127};
      const uint64_t e = high + kSuccessorStep[prev & 127];
      ok &= e > high && e != UINT64_MAX && keys[j] >= e;
      residual = std::max(residual, keys[j] - e);
      prev = keys[j];
    }
    b.successor_ok = ok;
    b.max_residual = residual;
  }
  if (any != 0) b.shift = std::min(b.shift, std::countr_zero(any));
  b.max_delta = most;
  b.prev = prev;
  b.count += count - i;
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
  for (uint32_t i = 0; i < count;) {
    if (open.count == kPackedBlock) {
      closed_.push_back(choose(open, shape_.key_kind));
      closed_bytes += block_bytes(open.count, closed_.back().width);
      open = OpenBlock{};
    }
    const uint32_t take = std::min(count - i, kPackedBlock - open.count);
    extend(open, keys + i, take, shape_.key_kind);
    i += take;
  }
  // Past the dictionary's room the page is column-wise from here on: it
  // stops counting rows (and a dictionary can never come back).  A group
  // that does not fit leaves the dictionary as it was: the entries before
  // it may need it to fit.
  const bool over_before = dict_over_;
  if (dict_add(vals, count)) {
    // Every row is one of the dictionary's: the columns' ranges are those
    // of its rows, and only the rows new to it can widen them (a mesh's
    // leaves repeat their material: at 2 Hz widening every row was 4% of
    // construct).
    for (size_t s : dict_added_) {
      widen_columns(vals + size_t{dict_slots_[s].first - keys_.size()} * shape_.payload, 1);
    }
  } else {
    dict_rollback();
    dict_over_ = true;
    widen_columns(vals, count);
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

namespace {

// Each field's range over `count` rows of `fields` fields of Size bytes:
// a field at a time, so its minimum and maximum are two running values in
// registers, with loads of a size known when compiled.
template <uint32_t Size>
void widen_uniform(const std::byte* vals, uint32_t count, size_t fields, uint64_t* lo,
                   uint64_t* hi) {
  const size_t row = Size * fields;
  for (size_t f = 0; f < fields; ++f) {
    uint64_t mn = lo[f], mx = hi[f];
    const std::byte* p = vals + f * Size;
    for (uint32_t i = 0; i < count; ++i, p += row) {
      const uint64_t v = load_field(p, Size);
      mn = std::min(mn, v);
      mx = std::max(mx, v);
    }
    lo[f] = mn, hi[f] = mx;
  }
}

}  // namespace

// The columns' ranges widened by a group's payloads (into scratch_cols_).
void PackedLeafBuilder::widen_columns(const std::byte* vals, uint32_t count) {
  const size_t nf = scratch_cols_.size();
  uint64_t lo[kMaxUniformFields], hi[kMaxUniformFields];
  if (nf <= kMaxUniformFields && (shape_.uniform_field == 4 || shape_.uniform_field == 1)) {
    for (size_t f = 0; f < nf; ++f) lo[f] = scratch_cols_[f].min, hi[f] = scratch_cols_[f].max;
    if (shape_.uniform_field == 4) {
      widen_uniform<4>(vals, count, nf, lo, hi);
    } else {
      widen_uniform<1>(vals, count, nf, lo, hi);
    }
    for (size_t f = 0; f < nf; ++f) scratch_cols_[f] = {lo[f], hi[f]};
    return;
  }
  for (uint32_t i = 0; i < count; ++i) {
    const std::byte* field = vals + size_t{i} * shape_.payload;
    for (size_t f = 0; f < nf; ++f) {
      const uint64_t v = load_field(field, shape_.field_sizes[f]);
      scratch_cols_[f] = {std::min(scratch_cols_[f].min, v), std::max(scratch_cols_[f].max, v)};
      field += shape_.field_sizes[f];
    }
  }
}

// Groups of 64 entries while they fit, then of 16, 4 and 1 (a group's
// checks cost about as much whatever its size): the page ends where adding
// one at a time would (add_group).
uint32_t PackedLeafBuilder::add_range(const uint64_t* keys, const std::byte* vals, uint32_t from,
                                      uint32_t to) {
  uint32_t i = from;
  for (uint32_t group = 64; group >= 1; group /= 4) {
    while (to - i >= group && add_group(keys + i, vals + size_t{i} * shape_.payload, group)) {
      i += group;
    }
  }
  return i;
}

namespace {

// One field's column: n values of `Size` bytes, `stride` apart from p, less
// min, w bits each.  The size known when compiled: a load of it, not a
// switch on it, for each value.
template <uint32_t Size>
void put_values(const std::byte* p, size_t stride, uint32_t n, uint64_t min, uint32_t w,
                std::byte* out) {
  BitWriter bits(out);
  for (uint32_t i = 0; i < n; ++i, p += stride) bits.put(load_field(p, Size) - min, w);
  bits.finish();
}

}  // namespace

void PackedLeafBuilder::put_column(const std::byte* p, size_t stride, uint32_t n, uint32_t size,
                                   const Column& c, uint32_t w, std::byte* out) {
  switch (size) {
    case 1: return put_values<1>(p, stride, n, c.min, w, out);
    case 2: return put_values<2>(p, stride, n, c.min, w, out);
    case 4: return put_values<4>(p, stride, n, c.min, w, out);
    default: return put_values<8>(p, stride, n, c.min, w, out);
  }
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
    if (w > 0)
      put_column(vals_.data() + field_off, shape_.payload, n, shape_.field_sizes[f], c, w, col);
    col += bits_to_bytes(uint64_t{n} * w);
    field_off += shape_.field_sizes[f];
  }
}

}  // namespace weaver::page
