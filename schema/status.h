// Status: the result of an operation that can fail, returned (never thrown)
// across layer boundaries. OK carries no message and costs one enum.
#pragma once

#include <string>
#include <utility>

namespace weaver {

class Status {
 public:
  enum class Code { kOk, kNotFound, kCorruption, kIOError, kInvalidArgument, kBusy, kInternal };

  Status() = default;
  static Status Ok() { return Status(); }
  static Status NotFound(std::string msg) { return Status(Code::kNotFound, std::move(msg)); }
  static Status Corruption(std::string msg) { return Status(Code::kCorruption, std::move(msg)); }
  static Status IOError(std::string msg) { return Status(Code::kIOError, std::move(msg)); }
  static Status InvalidArgument(std::string msg) {
    return Status(Code::kInvalidArgument, std::move(msg));
  }
  static Status Busy(std::string msg) { return Status(Code::kBusy, std::move(msg)); }
  // A broken promise between parts of weaver: a bug, not bad input.
  static Status Internal(std::string msg) { return Status(Code::kInternal, std::move(msg)); }

  bool ok() const { return code_ == Code::kOk; }
  bool is_not_found() const { return code_ == Code::kNotFound; }
  bool is_corruption() const { return code_ == Code::kCorruption; }
  bool is_io_error() const { return code_ == Code::kIOError; }
  bool is_invalid_argument() const { return code_ == Code::kInvalidArgument; }
  bool is_busy() const { return code_ == Code::kBusy; }
  Code code() const { return code_; }
  const std::string& message() const { return msg_; }

  // "corruption: <message>", or "ok".
  std::string to_string() const;

 private:
  Status(Code code, std::string msg) : code_(code), msg_(std::move(msg)) {}
  Code code_ = Code::kOk;
  std::string msg_;
};

inline std::string Status::to_string() const {
  switch (code_) {
    case Code::kOk: return "ok";
    case Code::kNotFound: return "not found: " + msg_;
    case Code::kCorruption: return "corruption: " + msg_;
    case Code::kIOError: return "I/O error: " + msg_;
    case Code::kInvalidArgument: return "invalid argument: " + msg_;
    case Code::kBusy: return "busy: " + msg_;
    case Code::kInternal: return "internal error: " + msg_;
  }
  return msg_;
}

}  // namespace weaver

// Returns from the enclosing function when `expr` is not OK.
#define WEAVER_RETURN_IF_ERROR(expr) \
  do {                               \
    ::weaver::Status _st = (expr);   \
    if (!_st.ok()) return _st;       \
  } while (0)
