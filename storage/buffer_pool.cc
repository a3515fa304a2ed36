#include "storage/buffer_pool.h"

#include <sys/mman.h>

#include <algorithm>
#include <cstring>
#include <new>

#include "storage/checksum.h"
#include "storage/page_format.h"

namespace weaver {
namespace {

size_t next_pow2(size_t v) {
  size_t p = 1;
  while (p < v) p <<= 1;
  return p;
}

void seal_page(std::byte* pg, uint32_t page_no, uint32_t page_size) {
  page::store32(pg + page::kPgNumber, page_no);
  pg[page::kPgVersion] = static_cast<std::byte>(page::kFormatVersion);
  page::store32(pg + page::kPgChecksum, checksum32(pg + 4, page_size - 4));
}

}  // namespace

BufferPool::BufferPool(File* file, uint32_t page_size, uint64_t budget_bytes)
    : file_(file), page_size_(page_size) {
  // The budget pays for the write staging buffer, then for frames with their
  // bookkeeping (the Frame, up to 4 hash slots of 8 bytes, 4 direct-map
  // entries of 4).
  const uint64_t staging = uint64_t{kMaxWriteRun} * page_size;
  const uint64_t per_frame =
      page_size + sizeof(Frame) + 4 * sizeof(uint64_t) + kDirectPagesPerFrame * sizeof(uint32_t);
  const uint64_t n = std::max<uint64_t>(
      kMinFrames, budget_bytes > staging ? (budget_bytes - staging) / per_frame : 0);
  // The frames' memory comes in chunks of about 2 MiB, each allocated when
  // the clock first reaches one of its frames (it hands out the empty
  // frames in order): a pool sized for a large budget over a small table
  // allocates what the table fills.  (Allocating the whole budget at once
  // cost little in a plain build, where untouched pages are never faulted
  // in, but the sanitizers pay for every byte allocated and freed.)
  chunk_shift_ = 0;
  while ((uint64_t{page_size} << (chunk_shift_ + 1)) <= kChunkBytes) ++chunk_shift_;
  chunks_.resize(((n - 1) >> chunk_shift_) + 1);
  staging_ = AlignedBytes(new (std::align_val_t{64}) std::byte[size_t{kMaxWriteRun} * page_size],
                          AlignedArrayDelete{64});
  frames_.resize(n);
  table_.assign(next_pow2(2 * n), 0);
  table_mask_ = table_.size() - 1;
  direct_.assign(kDirectPagesPerFrame * n, 0);
}

BufferPool::~BufferPool() = default;

void BufferPool::allocate_chunk(size_t chunk) {
  const size_t first = chunk << chunk_shift_;
  const size_t frames = std::min(frames_.size() - first, size_t{1} << chunk_shift_);
  const size_t bytes = frames * page_size_;
  // 2 MiB alignment lets the kernel back a chunk with a huge page: a large
  // pool then takes far fewer TLB misses and page faults.  Not the first
  // chunks: a huge page is zeroed whole at its first fault, and where the
  // kernel must first compact memory for one (its default for advised
  // regions) the fault stalls for milliseconds, while a command over a
  // small table touches a few of the chunk's pages (a 92-leaf extract: 9.8
  // ms of CPU with every chunk advised, 3.2 ms with the first two not).
  chunks_[chunk] = AlignedBytes(new (std::align_val_t{kChunkBytes}) std::byte[bytes],
                                AlignedArrayDelete{kChunkBytes});
#ifdef MADV_HUGEPAGE
  if (chunk >= kPlainChunks && bytes >= kChunkBytes) {
    ::madvise(chunks_[chunk].get(), bytes, MADV_HUGEPAGE);
  }
#endif
  for (size_t i = 0; i < frames; ++i)
    frames_[first + i].data = chunks_[chunk].get() + i * page_size_;
}

uint64_t BufferPool::memory_bytes() const {
  return frames_.size() * (page_size_ + sizeof(Frame)) + table_.size() * sizeof(uint64_t) +
         direct_.size() * sizeof(uint32_t) + size_t{kMaxWriteRun} * page_size_;
}

size_t BufferPool::slot_of(uint32_t page_no) const { return (page_no * 0x9E3779B1u) & table_mask_; }

Frame* BufferPool::lookup(uint32_t page_no) const {
  uint32_t entry = 0;  // frame index + 1
  if (page_no < direct_.size()) {
    entry = direct_[page_no];
  } else {
    for (size_t s = slot_of(page_no); table_[s] != 0; s = (s + 1) & table_mask_) {
      if (uint32_t(table_[s] >> 32) == page_no) {
        entry = uint32_t(table_[s]);
        break;
      }
    }
  }
  if (entry == 0) return nullptr;
  return const_cast<Frame*>(&frames_[entry - 1]);
}

void BufferPool::table_insert(uint32_t page_no, uint32_t frame_index) {
  if (page_no < direct_.size()) {
    direct_[page_no] = frame_index + 1;
    return;
  }
  size_t s = slot_of(page_no);
  while (table_[s] != 0) s = (s + 1) & table_mask_;
  table_[s] = (uint64_t{page_no} << 32) | (frame_index + 1);
}

// Backward-shift deletion keeps probe chains intact without tombstones.
void BufferPool::table_erase(uint32_t page_no) {
  if (page_no < direct_.size()) {
    direct_[page_no] = 0;
    return;
  }
  size_t s = slot_of(page_no);
  while (uint32_t(table_[s] >> 32) != page_no) s = (s + 1) & table_mask_;
  size_t hole = s;
  for (size_t j = (hole + 1) & table_mask_; table_[j] != 0; j = (j + 1) & table_mask_) {
    const size_t home = slot_of(uint32_t(table_[j] >> 32));
    // Move j into the hole if its home is not in the cyclic range (hole, j].
    const bool home_in_range = hole <= j ? (home > hole && home <= j) : (home > hole || home <= j);
    if (!home_in_range) {
      table_[hole] = table_[j];
      hole = j;
    }
  }
  table_[hole] = 0;
}

Status BufferPool::write_run_from(Frame* first) {
  // Gather first and the dirty, unpinned pages that follow it in page order.
  Frame* run[kMaxWriteRun];
  uint32_t n = 0;
  run[n++] = first;
  while (n < kMaxWriteRun) {
    Frame* f = lookup(first->page_no + n);
    if (f == nullptr || !f->dirty) break;
    run[n++] = f;
  }
  for (uint32_t i = 0; i < n; ++i) {
    std::byte* dst = staging_.get() + size_t{i} * page_size_;
    std::memcpy(dst, run[i]->data, page_size_);
    seal_page(dst, run[i]->page_no, page_size_);
  }
  WEAVER_RETURN_IF_ERROR(write_fully(*file_, page::page_offset(first->page_no, page_size_),
                                     staging_.get(), size_t{n} * page_size_));
  for (uint32_t i = 0; i < n; ++i) run[i]->dirty = false;
  stats_.pages_written += n;
  stats_.write_calls += 1;
  return Status::Ok();
}

void BufferPool::unpin_recycle(Frame* f) {
  if (--f->pins > 0) return;
  f->referenced = false;  // a later hit sets it again and saves the page
  // Bounded: a frame offered twice is harmless, the check below skips it.
  if (recycle_.size() < frames_.size())
    recycle_.push_back(static_cast<uint32_t>(f - frames_.data()));
}

Status BufferPool::find_victim(Frame** out) {
  while (!recycle_.empty()) {
    Frame& f = frames_[recycle_.back()];
    recycle_.pop_back();
    if (f.pins > 0 || f.referenced || f.page_no == 0) continue;
    if (f.dirty) WEAVER_RETURN_IF_ERROR(write_run_from(&f));
    table_erase(f.page_no);
    f.page_no = 0;
    *out = &f;
    return Status::Ok();
  }
  const size_t n = frames_.size();
  for (size_t step = 0; step < 3 * n; ++step) {
    Frame& f = frames_[clock_hand_];
    clock_hand_ = clock_hand_ + 1 == n ? 0 : clock_hand_ + 1;
    if (f.pins > 0) continue;
    if (f.referenced) {
      f.referenced = false;
      continue;
    }
    if (f.dirty) WEAVER_RETURN_IF_ERROR(write_run_from(&f));
    if (f.page_no != 0) table_erase(f.page_no);
    f.page_no = 0;
    if (f.data == nullptr) allocate_chunk(size_t(&f - frames_.data()) >> chunk_shift_);
    *out = &f;
    return Status::Ok();
  }
  return Status::Busy(file_->name() + ": buffer pool exhausted: every frame is pinned");
}

Status BufferPool::read_page(uint32_t page_no, Frame* f) {
  const uint64_t off = page::page_offset(page_no, page_size_);
  Status st = read_fully(*file_, off, f->data, page_size_);
  const std::string where = file_->name() + ": page " + std::to_string(page_no);
  if (!st.ok()) {
    if (st.is_corruption()) return Status::Corruption(where + ": file is truncated");
    return Status::IOError(where + ": " + st.message());
  }
  if (checksums_enforced() &&
      page::load32(f->data + page::kPgChecksum) != checksum32(f->data + 4, page_size_ - 4)) {
    return Status::Corruption(where + ": checksum mismatch");
  }
  if (page::load32(f->data + page::kPgNumber) != page_no) {
    return Status::Corruption(where + ": page holds the content of page " +
                              std::to_string(page::load32(f->data + page::kPgNumber)));
  }
  if (static_cast<uint32_t>(f->data[page::kPgVersion]) != page::kFormatVersion) {
    return Status::Corruption(where + ": unsupported page format version " +
                              std::to_string(static_cast<int>(f->data[page::kPgVersion])));
  }
  stats_.pages_read += 1;
  return Status::Ok();
}

const std::byte* BufferPool::hit(Frame* f, uint32_t prefetch_bytes) {
  // Ask for the lines the caller reads next now, all at once, from the
  // page's address alone: they, and the frame's own miss, overlap instead
  // of following one another.
  const std::byte* data = data_of(f);
  for (uint32_t off = 0; off < prefetch_bytes; off += 64) __builtin_prefetch(data + off);
  ++stats_.hits;
  f->referenced = true;
  return data;
}

const std::byte* BufferPool::peek(uint32_t page_no, uint32_t prefetch_bytes) {
  Frame* f = lookup(page_no);
  return f == nullptr ? nullptr : hit(f, prefetch_bytes);
}

Status BufferPool::fetch(uint32_t page_no, Frame** out, uint32_t prefetch_bytes) {
  if (Frame* f = lookup(page_no)) {
    hit(f, prefetch_bytes);
    ++f->pins;
    *out = f;
    return Status::Ok();
  }
  ++stats_.misses;
  Frame* f = nullptr;
  WEAVER_RETURN_IF_ERROR(find_victim(&f));
  Status st = read_page(page_no, f);
  if (!st.ok()) return st;  // the frame stays empty
  f->page_no = page_no;
  f->pins = 1;
  f->dirty = false;
  f->referenced = true;
  table_insert(page_no, static_cast<uint32_t>(f - frames_.data()));
  *out = f;
  return Status::Ok();
}

Status BufferPool::create(uint32_t page_no, Frame** out) {
  Frame* f = lookup(page_no);
  if (f == nullptr) {
    WEAVER_RETURN_IF_ERROR(find_victim(&f));
    f->page_no = page_no;
    table_insert(page_no, static_cast<uint32_t>(f - frames_.data()));
  }
  std::memset(f->data, 0, page_size_);
  f->pins += 1;
  f->dirty = true;
  f->referenced = true;
  *out = f;
  return Status::Ok();
}

Status BufferPool::flush() {
  std::vector<Frame*> dirty;
  for (Frame& f : frames_) {
    if (f.dirty) dirty.push_back(&f);
  }
  std::sort(dirty.begin(), dirty.end(),
            [](const Frame* a, const Frame* b) { return a->page_no < b->page_no; });
  for (Frame* f : dirty) {
    if (f->dirty) WEAVER_RETURN_IF_ERROR(write_run_from(f));
  }
  return Status::Ok();
}

}  // namespace weaver
