// Runs the weaver binary as a user does, for the tests of its command line.
#pragma once

#include <sys/wait.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <string>

#include "test_util.h"

namespace weaver::testing {

struct CommandRun {
  int code;         // exit status; -1 if killed by a signal
  std::string out;  // stdout
  std::string err;  // stderr
};

// `weaver ARGS` through the shell; `env` (e.g. "WEAVER_FAIL_AT=3 ") and
// `prefix` (e.g. "ulimit -v 100000; ") go before it.
inline CommandRun run(const std::string& args, const std::string& prefix = "") {
  TempDir tmp;
  const std::string cmd =
      prefix + std::string(WEAVER_BINARY) + " " + args + " 2>" + tmp.file("err");
  FILE* p = ::popen(cmd.c_str(), "r");
  CommandRun r{};
  std::array<char, 4096> buf;
  size_t n;
  while ((n = std::fread(buf.data(), 1, buf.size(), p)) > 0) r.out.append(buf.data(), n);
  const int status = ::pclose(p);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream e(tmp.file("err"));
  r.err.assign(std::istreambuf_iterator<char>(e), {});
  return r;
}

inline int lines(const std::string& s) {
  return static_cast<int>(std::count(s.begin(), s.end(), '\n'));
}

}  // namespace weaver::testing
