// Command-line option values: sizes, counts, numbers, lists, and argument
// vectors split on NUL bytes.
#include <string>
#include <vector>

#include "util/args.h"

using namespace weaver;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  uint64_t u = 0;
  double d = 0;
  std::vector<uint64_t> ul;
  std::vector<double> dl;
  (void)parse_bytes(text, "--memory", &u);
  (void)parse_count(text, "--max-elements", &u);
  (void)parse_u64(text, "--threads", &u);
  (void)parse_double(text, "--freq", &d);
  (void)parse_u64_list(text, "--blocks", 3, &ul);
  (void)parse_double_list(text, "--domain", 3, &dl);
  std::vector<std::string> words;
  size_t start = 0;
  for (size_t i = 0; i <= text.size(); ++i) {
    if (i == text.size() || text[i] == '\0')
      words.push_back(text.substr(start, i - start)), start = i + 1;
  }
  std::vector<char*> argv;
  for (std::string& w : words) argv.push_back(w.data());
  ParsedArgs args;
  (void)parse_args(static_cast<int>(argv.size()), argv.data(), 0, {"memory", "freq"}, {"json"},
                   &args);
  return 0;
}
