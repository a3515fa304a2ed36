// Packed leaves: the reader (PackedLeaf): a page opened in place, keys
// decoded a block at a time, payloads from their columns; the dictionary's
// rows in packed_row_dictionary.cc (format: storage/packed_leaf.h).
#include <algorithm>
#include <bit>
#include <cstring>

#include "storage/packed_bits.h"
#include "storage/packed_leaf.h"
#include "storage/page_format.h"
#include "storage/page_search.h"

namespace weaver::page {
using namespace packed;

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

namespace {

// Mode 1's keys after out[0], as the loop of successor() computes them,
// where no key is of level 20 and no subtree reaches the root's end (true
// returned; else false, and out[1..] are to be decoded that way).
// successor(k) has its level slot zero, so key i's slot is residual i's
// low 7 bits and its high bits are the last key's high bits plus the last
// key's subtree span (from the last residual's slot) plus the residual's
// high bits: one addition a key waits on, not the whole of successor()
// (the 2 Hz extract decodes 1.34G keys so).
bool successor_run(const std::byte* bits, uint32_t w, uint32_t cnt, uint64_t* out) {
  constexpr uint64_t kSlot = 127;
  uint64_t high = out[0] & ~kSlot, slot = out[0] & kSlot;
  bool ok = true;
  for (uint32_t i = 1; i < cnt; ++i) {
    const uint64_t r = read_bits(bits, uint64_t{i - 1} * w, w);
    // (A level 20 key's successor is the key plus one, not a new slot.)
    ok &= slot < kKeyLevel20Slot;
    // Neither the root's step (0) nor a span past the root's end (it
    // wraps) moves past the key: successor()'s UINT64_MAX.
    const uint64_t end = high + kSuccessorStep[slot];
    ok &= end > high;
    high = end + (r & ~kSlot);
    slot = r & kSlot;
    out[i] = high | slot;
  }
  return ok;
}

}  // namespace

bool PackedLeaf::block_keys(uint32_t j, uint64_t* out, uint32_t* cnt_out) const {
  uint32_t cnt = 0, w = 0;
  uint8_t mode = 0;
  const std::byte* bits = block_bits(j, &cnt, &w, &mode);
  if (bits == nullptr) return false;
  uint64_t k = load64(bases_ + 8 * size_t{j});
  out[0] = k;
  if (mode & kModeSuccessor) {
    if (!successor_run(bits, w, cnt, out)) {
      for (uint32_t i = 1; i < cnt; ++i)
        out[i] = k = successor(k) + read_bits(bits, (i - 1) * w, w);
    }
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

bool PackedLeaf::floor_block(uint64_t k, uint64_t* keys, uint32_t* cnt, uint64_t* limit) const {
  const uint32_t c = upper_bound(bases_, m_, k);
  *cnt = 0;
  *limit = c < m_ ? load64(bases_ + 8 * size_t{c}) : 0;
  return c == 0 || block_keys(c - 1, keys, cnt);
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
