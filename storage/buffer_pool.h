// A buffer pool of fixed-size pages over one File, bounded by a byte budget.
//
// Pages are cached in frames and replaced by CLOCK.  Every page read from
// disk is verified (checksum, page number, format version) before anyone
// sees it; every page written gets its checksum set.  Dirty pages are written
// back when evicted or on flush(), coalescing runs of consecutive page
// numbers into one write, so sequentially allocated pages stream to disk.
//
// Not thread-safe: one pool serves one thread.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "schema/status.h"
#include "storage/file.h"

namespace weaver {

struct Frame {
  std::byte* data = nullptr;
  uint32_t page_no = 0;  // 0: the frame is empty
  uint32_t pins = 0;
  bool dirty = false;
  bool referenced = false;
};

struct PoolStats {
  uint64_t hits = 0, misses = 0, pages_read = 0, pages_written = 0, write_calls = 0;
};

// Frees memory from an aligned array new.
struct AlignedArrayDelete {
  size_t alignment;
  void operator()(std::byte* p) const { ::operator delete[](p, std::align_val_t{alignment}); }
};
using AlignedBytes = std::unique_ptr<std::byte[], AlignedArrayDelete>;

class BufferPool {
 public:
  // The pool holds its frames, their bookkeeping and a write staging buffer
  // of kMaxWriteRun pages within budget_bytes (memory_bytes() <= budget),
  // but keeps at least kMinFrames frames whatever the budget, so that a
  // root-to-leaf path plus split siblings always fits.
  static constexpr uint32_t kMinFrames = 64;
  // Longest run of consecutive dirty pages coalesced into one write.
  static constexpr uint32_t kMaxWriteRun = 64;
  // Bytes of a page prefetched on a hit unless the caller says otherwise:
  // the header line, which every caller reads first.
  static constexpr uint32_t kPrefetchBytes = 64;

  BufferPool(File* file, uint32_t page_size, uint64_t budget_bytes);
  ~BufferPool();
  BufferPool(const BufferPool&) = delete;
  BufferPool& operator=(const BufferPool&) = delete;

  // Pins page_no (>= 1), reading and verifying it on a miss.  On a hit the
  // first prefetch_bytes of the page are prefetched (a caller that will
  // search the page asks for its key column, one that reads it whole for
  // all of it).
  Status fetch(uint32_t page_no, Frame** out, uint32_t prefetch_bytes = kPrefetchBytes);
  // Pins a frame for a page that has no valid content on disk yet (a new or
  // reused page): zero-filled and dirty.  REQUIRES: page_no not pinned.
  Status create(uint32_t page_no, Frame** out);
  void unpin(Frame* f) { --f->pins; }
  // A cached page's bytes without a pin, prefetched as fetch() does, or null
  // when the page is not in the pool (the caller then fetches it).  Valid
  // until the pool's next fetch or create: for a lookup that reads one page
  // and is done with it, and so needs no pin to keep it.
  const std::byte* peek(uint32_t page_no, uint32_t prefetch_bytes);
  // Unpins a page the caller is done with for good (a scan moving on): it
  // becomes the next victim, so a long scan recycles a few frames instead of
  // flushing the pool, and never faults in fresh memory.
  void unpin_recycle(Frame* f);

  // Writes every dirty page back (does not sync the file).
  Status flush();

  // A frame's page bytes, computed from its index and the chunk table (a
  // word per 2 MiB of pool: 4 KiB for 1 GiB, and hot): unlike f->data,
  // reading it needs no load from the frame (a cache miss on a random
  // lookup in a large pool).
  std::byte* data_of(const Frame* f) const {
    const size_t i = size_t(f - frames_.data());
    return chunks_[i >> chunk_shift_].get() + (i & ((size_t{1} << chunk_shift_) - 1)) * page_size_;
  }

  uint32_t page_size() const { return page_size_; }
  uint64_t frame_count() const { return frames_.size(); }
  uint64_t memory_bytes() const;
  const PoolStats& stats() const { return stats_; }
  File* file() const { return file_; }

 private:
  Status find_victim(Frame** out);
  // Allocates the frames' memory of chunk `chunk` (frames chunk << chunk_shift_ on).
  void allocate_chunk(size_t chunk);
  Status write_run_from(Frame* first);
  Status read_page(uint32_t page_no, Frame* f);
  // A pool hit on f: counts it, marks it referenced, prefetches its page.
  const std::byte* hit(Frame* f, uint32_t prefetch_bytes);
  // Pages covered by the direct map, per frame (see direct_).
  static constexpr uint32_t kDirectPagesPerFrame = 4;
  Frame* lookup(uint32_t page_no) const;
  void table_insert(uint32_t page_no, uint32_t frame_index);
  void table_erase(uint32_t page_no);
  size_t slot_of(uint32_t page_no) const;

  File* file_;
  uint32_t page_size_;
  static constexpr size_t kChunkBytes = size_t{2} << 20;
  // Chunks given 4 KiB pages before the pool asks for huge ones (allocate_chunk).
  static constexpr size_t kPlainChunks = 2;
  std::vector<AlignedBytes> chunks_;  // the frames' pages, 2^chunk_shift_ frames a chunk
  int chunk_shift_ = 0;
  AlignedBytes staging_{nullptr, AlignedArrayDelete{64}};  // kMaxWriteRun pages, coalesced writes
  std::vector<Frame> frames_;
  std::vector<uint32_t> recycle_;  // frame indices offered by unpin_recycle
  // Where a cached page's frame is: pages below direct_.size() in a direct
  // map (frame index + 1, 0 = not cached), the rest in a hash table.  The
  // map covers 4 pages per frame, so any file the pool holds a quarter of is
  // found without hashing, and the map's live part (4 bytes per file page)
  // stays in the CPU cache while a hash slot per frame would miss it.
  std::vector<uint32_t> direct_;
  // Open addressing: page_no << 32 | (frame index + 1), 0 = empty.  The page
  // number in the slot lets a lookup skip the frame (a cache miss) on a probe.
  std::vector<uint64_t> table_;
  size_t table_mask_ = 0;
  size_t clock_hand_ = 0;
  PoolStats stats_;
};

// Pins a frame for its lifetime.
class PageRef {
 public:
  PageRef() = default;
  PageRef(BufferPool* pool, Frame* f) : pool_(pool), f_(f) {}
  PageRef(PageRef&& o) noexcept : pool_(o.pool_), f_(o.f_) { o.f_ = nullptr; }
  PageRef& operator=(PageRef&& o) noexcept {
    if (this != &o) {
      reset();
      pool_ = o.pool_;
      f_ = o.f_;
      o.f_ = nullptr;
    }
    return *this;
  }
  ~PageRef() { reset(); }
  void reset() {
    if (f_ != nullptr) pool_->unpin(f_);
    f_ = nullptr;
  }
  // Like reset(), but tells the pool the page will not be needed again soon.
  void recycle() {
    if (f_ != nullptr) pool_->unpin_recycle(f_);
    f_ = nullptr;
  }
  std::byte* data() const { return pool_->data_of(f_); }
  uint32_t page_no() const { return f_->page_no; }
  void mark_dirty() const { f_->dirty = true; }
  explicit operator bool() const { return f_ != nullptr; }

 private:
  BufferPool* pool_ = nullptr;
  Frame* f_ = nullptr;
};

}  // namespace weaver
