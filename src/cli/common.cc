#include <cstdio>

#include "cli/cli.h"

namespace weaver::cli {

int report(const std::string& command, const Status& st) {
  std::string msg = st.message();
  if (st.is_corruption()) msg = "corrupt data: " + msg;
  if (st.is_io_error()) msg = "I/O error: " + msg;
  std::fprintf(stderr, "weaver %s: %s\n", command.c_str(), msg.c_str());
  return 1;
}

int usage_error(const std::string& command, const std::string& message, const char* /*usage*/) {
  std::fprintf(stderr, "weaver %s: %s (see 'weaver %s --help')\n", command.c_str(),
               message.c_str(), command.c_str());
  return 2;
}

Status memory_option(const ParsedArgs& args, uint64_t* bytes) {
  *bytes = kDefaultMemory;
  if (!args.values.count("memory")) return Status::Ok();
  WEAVER_RETURN_IF_ERROR(parse_bytes(args.values.at("memory"), "--memory", bytes));
  if (*bytes < (1u << 20)) return Status::InvalidArgument("--memory must be at least 1M");
  return Status::Ok();
}

Status threads_option(const ParsedArgs& args, int default_threads, int* threads) {
  *threads = default_threads;
  if (!args.values.count("threads")) return Status::Ok();
  uint64_t n = 0;
  WEAVER_RETURN_IF_ERROR(parse_u64(args.values.at("threads"), "--threads", &n));
  if (n < 1 || n > 256) return Status::InvalidArgument("--threads must be 1..256");
  *threads = static_cast<int>(n);
  return Status::Ok();
}

}  // namespace weaver::cli
