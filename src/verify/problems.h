// The problem list of a verify run, capped so that a badly damaged database
// does not print millions of lines.
#pragma once

#include <string>

#include "verify/verify.h"

namespace weaver {

class Problems {
 public:
  Problems(const VerifyOptions& o, VerifyReport* r) : options_(o), report_(r) {}
  // Records a problem; false once the cap is reached (callers stop looking).
  bool add(std::string text) {
    if (full()) return false;
    report_->problems.push_back(std::move(text));
    return !full();
  }
  bool full() const { return report_->problems.size() >= options_.max_problems; }
  void progress(const std::string& line) const {
    if (options_.progress) options_.progress(line);
  }

 private:
  const VerifyOptions& options_;
  VerifyReport* report_;
};

}  // namespace weaver
