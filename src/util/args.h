// Command-line parsing shared by the weaver subcommands.
#pragma once

#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "schema/status.h"

namespace weaver {

struct ParsedArgs {
  std::vector<std::string> positional;
  std::map<std::string, std::string> values;  // --name value
  std::set<std::string> flags;                // --name
  bool help = false;                          // -h / --help seen

  bool has(const std::string& name) const { return values.count(name) || flags.count(name); }
};

// Splits argv[start..] into positionals, options that take a value and
// boolean flags; anything else starting with "--" is an error, and so is an
// option given twice (rather than silently taking the last value).
Status parse_args(int argc, char** argv, int start, const std::set<std::string>& value_options,
                  const std::set<std::string>& flag_options, ParsedArgs* out);

// "256M", "2G", "512K", "1048576" (K/M/G are powers of 1024; a trailing "B"
// or "iB" is accepted).  `what` names the argument in the error; sizes of
// 2^64 bytes or more are refused, never wrapped.
Status parse_bytes(const std::string& text, const std::string& what, uint64_t* out);
// Bytes of physical memory of this machine (0 if unknown): the ceiling of
// every --memory.
uint64_t physical_memory();
// "5000000", "5M", "5G": K/M/G/T are powers of 1000.
Status parse_count(const std::string& text, const std::string& what, uint64_t* out);
Status parse_u64(const std::string& text, const std::string& what, uint64_t* out);
Status parse_double(const std::string& text, const std::string& what, double* out);
// "a,b,c" into n numbers.
Status parse_u64_list(const std::string& text, const std::string& what, size_t n,
                      std::vector<uint64_t>* out);
Status parse_double_list(const std::string& text, const std::string& what, size_t n,
                         std::vector<double>* out);

}  // namespace weaver
