// The queries of `weaver query DB ...`, run against an open Explorer so that
// the shell (`weaver shell DB`) runs the very same commands on a database it
// opened once.
#pragma once

#include <cstdio>
#include <string>
#include <vector>

#include "cli/query_output.h"
#include "query/explorer.h"
#include "util/args.h"

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
  // A --points batch's points answered at a time (0: the Explorer's).
  size_t batch_points = 0;
  // range --list: one page of the leaves, those from element id list_from
  // on, at most list_limit; then *list_next (if set) is the id of the first
  // leaf past the page (UINT64_MAX when it ends the box) and *list_count
  // (if set) the count of the whole box.
  uint64_t list_from = 0, list_limit = UINT64_MAX;
  uint64_t* list_next = nullptr;
  uint64_t* list_count = nullptr;
};

// Runs one query: words[0] is its name ("locate", "neighbors", ...), the
// rest its arguments and options.  Answers go to out; an error is one line
// on err, "<who>: <message>".  Returns 0, 1 (an error, or bad lines in a
// points file) or 2 (bad usage).
int run_query(Explorer& ex, const std::vector<std::string>& words, const QuerySettings& settings,
              std::FILE* out, std::FILE* err, const std::string& who);

// Runs a query whose words were parsed already, or made by a program rather
// than typed (weaver serve's, from values it parsed itself): args as
// parse_args leaves them, the query's name first among the positional.
int run_parsed_query(Explorer& ex, ParsedArgs args, const QuerySettings& settings, std::FILE* out,
                     std::FILE* err, const std::string& who);

// Checks a query's words without a database: its name, options and the
// count and syntax of its numbers.  InvalidArgument saying what is wrong.
Status check_query(const std::vector<std::string>& words);

// The queries and their options, for --help and the shell's .help.
extern const char kQueryHelp[];

}  // namespace weaver::cli
