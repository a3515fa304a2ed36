// The queries of `weaver query DB ...`, run against an open Explorer so that
// the shell (`weaver shell DB`) runs the very same commands on a database it
// opened once.
#pragma once

#include <cstdio>
#include <string>
#include <vector>

#include "cli/query_output.h"
#include "query/explorer.h"

namespace weaver::cli {

// What a query inherits unless its own options say otherwise (the shell's
// .mode and .units).
struct QuerySettings {
  OutputMode mode = OutputMode::kText;
  bool metres = false;
  // Where `--points -` reads: the process's stdin unless set (the shell
  // hands it the lines that follow the command).
  std::FILE* points_stdin = nullptr;
  // More Explorers on the same state, for a --points batch to share its
  // work with (PointBatchOptions::helpers).
  std::vector<Explorer*> helpers;
};

// Runs one query: words[0] is its name ("locate", "neighbors", ...), the
// rest its arguments and options.  Answers go to out; an error is one line
// on err, "<who>: <message>".  Returns 0, 1 (an error, or bad lines in a
// points file) or 2 (bad usage).
int run_query(Explorer& ex, const std::vector<std::string>& words, const QuerySettings& settings,
              std::FILE* out, std::FILE* err, const std::string& who);

// Checks a query's words without a database: its name, options and the
// count and syntax of its numbers.  InvalidArgument saying what is wrong.
Status check_query(const std::vector<std::string>& words);

// The queries and their options, for --help and the shell's .help.
extern const char kQueryHelp[];

}  // namespace weaver::cli
