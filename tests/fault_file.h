// A File wrapper for tests: can cap each transfer (short reads and writes),
// fail I/O after a number of calls, and count calls.
#pragma once

#include <algorithm>
#include <memory>

#include "storage/file.h"

namespace weaver::testing {

class FaultFile final : public File {
 public:
  explicit FaultFile(std::unique_ptr<File> base) : base_(std::move(base)) {}

  size_t max_transfer = SIZE_MAX;  // short reads/writes above this size
  int64_t fail_writes_after = -1;  // -1: never
  int64_t fail_reads_after = -1;
  int64_t writes = 0, reads = 0;

  Status read_at(uint64_t offset, void* buf, size_t n, size_t* done) override {
    if (fail_reads_after >= 0 && reads >= fail_reads_after) {
      return Status::IOError(name() + ": injected read failure");
    }
    ++reads;
    return base_->read_at(offset, buf, std::min(n, max_transfer), done);
  }
  Status write_at(uint64_t offset, const void* buf, size_t n, size_t* done) override {
    if (fail_writes_after >= 0 && writes >= fail_writes_after) {
      return Status::IOError(name() + ": injected write failure");
    }
    ++writes;
    return base_->write_at(offset, buf, std::min(n, max_transfer), done);
  }
  Status sync() override { return base_->sync(); }
  Status size(uint64_t* out) override { return base_->size(out); }
  Status truncate(uint64_t size) override { return base_->truncate(size); }
  const std::string& name() const override { return base_->name(); }

 private:
  std::unique_ptr<File> base_;
};

}  // namespace weaver::testing
