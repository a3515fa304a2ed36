// Packed leaves' second payload coding, the row dictionary: the page's
// distinct payload rows once each and a bit-packed index per entry, chosen
// page by page where it is smaller than the columns.  Both halves: the
// builder's (which rows, and the index written) and the reader's (format:
// storage/packed_leaf.h).
#include <algorithm>
#include <bit>
#include <cstring>

#include "storage/packed_bits.h"
#include "storage/packed_leaf.h"
#include "storage/page_format.h"

namespace weaver::page {
using namespace packed;

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
  uint32_t ordinal = dict_ordinal_.empty() ? 0 : dict_ordinal_.back();
  for (uint32_t i = 0; i < count; ++i) {
    const std::byte* row = vals + size_t{i} * size;
    if (prev == nullptr || !rows_equal(prev, row, size)) {
      prev = row;
      const size_t s = dict_probe(row, vals);
      if (dict_slots_[s].first == UINT32_MAX) {
        if (dict_first_.size() == dict_max_rows_) return false;
        const auto entry = static_cast<uint32_t>(keys_.size() + i);
        dict_slots_[s] = {entry, static_cast<uint32_t>(dict_first_.size())};
        dict_first_.push_back(entry);
        dict_added_.push_back(s);
      }
      ordinal = dict_slots_[s].ordinal;
    }
    dict_ordinal_.push_back(ordinal);
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
  if (dict_ordinal_.size() > keys_.size()) dict_ordinal_.resize(keys_.size());
}

uint64_t PackedLeafBuilder::dictionary_bytes(size_t n, size_t dict_rows) const {
  if (dict_over_ || dict_rows == 0) return UINT64_MAX;
  const auto w = static_cast<uint64_t>(std::bit_width(dict_rows - 1));
  return bits_to_bytes(n * w) + uint64_t{dict_rows} * shape_.payload;
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
  for (uint32_t i = 0; i < n; ++i) bits.put(dict_ordinal_[i], w);  // every entry's: not over
  bits.finish();
  std::byte* out = col + bits_to_bytes(uint64_t{n} * w);
  for (uint32_t first : dict_first_) {
    std::memcpy(out, payload(first), shape_.payload);
    out += shape_.payload;
  }
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

template bool PackedLeaf::decode_dictionary<12>(std::byte* vals) const;
template bool PackedLeaf::decode_dictionary<20>(std::byte* vals) const;
template bool PackedLeaf::decode_dictionary<0>(std::byte* vals) const;

}  // namespace weaver::page
