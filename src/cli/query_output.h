// How query answers are printed: the output modes of `weaver query` and of
// the shell's `.mode`, in the manner of the sqlite3 shell.
//   text   sentences for one answer, a table for several (the default)
//   table  aligned columns under a header
//   json   one JSON document: an array of row objects, or one object where
//          the answer is one thing (as sqlite3's -json and duckdb's -json)
//   jsonl  one JSON object a line (JSON Lines, also called ndjson), streamed
//   csv    a header, then one line per answer (RFC 4180 quoting)
//   tsv    the same with tabs
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "schema/status.h"

namespace weaver::cli {

enum class OutputMode { kText, kTable, kJson, kJsonl, kCsv, kTsv };

// "text", "table", "json", "jsonl" (or "ndjson"), "csv", "tsv".
Status parse_output_mode(const std::string& name, OutputMode* out);
const char* output_mode_name(OutputMode m);

// One value of an answer: a number, a string, a list of numbers, or null.
struct Cell {
  enum class Kind { kNumber, kString, kList, kNull };
  Kind kind = Kind::kNull;
  std::string text;                // number or string
  std::vector<std::string> items;  // a list's numbers

  static Cell number(uint64_t v) { return {Kind::kNumber, std::to_string(v), {}}; }
  static Cell number(double v);  // shortest text that reads back the same
  static Cell number(float v);   // the same for a float (vp, vs, rho are stored as such)
  static Cell string(std::string s) { return {Kind::kString, std::move(s), {}}; }
  static Cell list(std::vector<std::string> items) { return {Kind::kList, "", std::move(items)}; }
  static Cell null() { return {}; }
};

// Answers with named columns: every row has one cell per column.
struct Table {
  std::vector<std::string> columns;
  std::vector<std::vector<Cell>> rows;
  // The answer is one thing (an element, a node, a count): JSON prints its
  // one row as an object, not as an array of one.
  bool one = false;
};

// Prints t in mode (kText prints it as kTable).  Header lines (table, csv,
// tsv) only when the table has columns.
void print_table(const Table& t, OutputMode mode, std::FILE* out);

// A table printed a row at a time, as print_table prints it whole: json,
// jsonl, csv and tsv rows go out as they come (an answer of any length in
// little memory); text and table hold them, to align their columns.
class TableStream {
 public:
  TableStream(OutputMode mode, std::vector<std::string> columns, std::FILE* out);
  void row(std::vector<Cell> cells);
  // After the last row: closes a JSON array, prints the rows held.
  void finish();

 private:
  OutputMode mode_;
  std::FILE* out_;
  Table held_;  // the columns, and in text or table mode the rows
  uint64_t rows_ = 0;
};

// A cell as JSON and as CSV text; a list as its items joined by spaces.
std::string plain_text(const Cell& c);
std::string json_text(const Cell& c);
std::string csv_text(const Cell& c, char separator);

}  // namespace weaver::cli
