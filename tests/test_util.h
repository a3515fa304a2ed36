// Helpers shared by the tests.
#pragma once

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "schema/status.h"

namespace weaver::testing {

// WEAVER_TEST_SCALE=small (set for sanitizer runs) shrinks the long loops.
inline bool small_scale() {
  const char* s = std::getenv("WEAVER_TEST_SCALE");
  return s != nullptr && std::string(s) == "small";
}
inline uint64_t scaled(uint64_t full, uint64_t small) { return small_scale() ? small : full; }

// The whole of a file ("" when it cannot be read).
inline std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// ::testing::TempDir() + name, emptied (removed if there): a database path
// a test may create, left behind for a look after a failure.
inline std::string fresh_path(const std::string& name) {
  const std::string path = ::testing::TempDir() + name;
  std::filesystem::remove_all(path);
  return path;
}

// A fresh, empty directory removed at scope exit.
class TempDir {
 public:
  TempDir() {
    std::string tmpl = (std::filesystem::temp_directory_path() / "weaver-test-XXXXXX").string();
    path_ = ::mkdtemp(tmpl.data());
  }
  ~TempDir() { std::filesystem::remove_all(path_); }
  const std::string& path() const { return path_; }
  std::string file(const std::string& name) const { return path_ + "/" + name; }

 private:
  std::string path_;
};

}  // namespace weaver::testing

#define ASSERT_OK(expr)                                      \
  do {                                                       \
    const ::weaver::Status _s = (expr);                      \
    ASSERT_TRUE(_s.ok()) << #expr << ": " << _s.to_string(); \
  } while (0)
#define EXPECT_OK(expr)                                      \
  do {                                                       \
    const ::weaver::Status _s = (expr);                      \
    EXPECT_TRUE(_s.ok()) << #expr << ": " << _s.to_string(); \
  } while (0)
