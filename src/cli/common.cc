#include <algorithm>
#include <cstdio>
#include <thread>

#include "cli/cli.h"

namespace weaver::cli {

std::string error_text(const Status& st) {
  if (st.is_corruption()) return "corrupt data: " + st.message();
  if (st.is_io_error()) return "I/O error: " + st.message();
  return st.message();
}

int report(const std::string& command, const Status& st) {
  std::fprintf(stderr, "weaver %s: %s\n", command.c_str(), error_text(st).c_str());
  return 1;
}

int usage_error(const std::string& command, const std::string& message, const char* /*usage*/) {
  std::fprintf(stderr, "weaver %s: %s (see 'weaver %s --help')\n", command.c_str(), message.c_str(),
               command.c_str());
  return 2;
}

Status outside_option(const ParsedArgs& args, bool* error) {
  *error = false;
  if (!args.values.count("outside")) return Status::Ok();
  const std::string& v = args.values.at("outside");
  if (v != "clamp" && v != "error") {
    return Status::InvalidArgument("--outside must be clamp or error, not '" + v + "'");
  }
  *error = v == "error";
  return Status::Ok();
}

Status memory_option(const ParsedArgs& args, MemoryBudget* budget) {
  *budget = MemoryBudget();
  if (!args.values.count("memory")) return Status::Ok();
  uint64_t bytes = 0;
  WEAVER_RETURN_IF_ERROR(parse_bytes(args.values.at("memory"), "--memory", &bytes));
  if (bytes < MemoryBudget::kMinBytes)
    return Status::InvalidArgument("--memory must be at least 1M");
  const uint64_t machine = physical_memory();
  if (machine > 0 && bytes > machine) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "--memory %s is more than this machine's memory (%.1f GiB)",
                  args.values.at("memory").c_str(), machine / double(1ull << 30));
    return Status::InvalidArgument(buf);
  }
  *budget = MemoryBudget(bytes);
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

Status balance_algorithm_option(const ParsedArgs& args, BalanceOptions::Algorithm* algorithm) {
  using Algorithm = BalanceOptions::Algorithm;
  *algorithm = Algorithm::kAuto;
  if (!args.values.count("algorithm")) return Status::Ok();
  const std::string& a = args.values.at("algorithm");
  if (a == "windows") {
    *algorithm = Algorithm::kWindows;
  } else if (a == "closure") {
    *algorithm = Algorithm::kClosure;
  } else if (a != "auto") {
    return Status::InvalidArgument("--algorithm must be auto, windows or closure");
  }
  return Status::Ok();
}

Status balance_model_option(const ParsedArgs& args, std::vector<std::string>* model_dirs) {
  if (!args.values.count("model")) return Status::Ok();
  const std::string& m = args.values.at("model");
  if (m.rfind("db:", 0) != 0 || m.size() == 3) {
    return Status::InvalidArgument(
        "--model takes db:PATH, the model database the octants were "
        "built from");
  }
  model_dirs->push_back(m.substr(3));
  return Status::Ok();
}

int default_threads() {
  return static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}

}  // namespace weaver::cli
