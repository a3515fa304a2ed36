#include "cli/query_output.h"

#include <algorithm>
#include <charconv>

#include "util/json_string.h"

namespace weaver::cli {

namespace {
// In OutputMode's order.
const char* const kModeNames[] = {"text", "table", "json", "jsonl", "csv", "tsv"};
}  // namespace

Status parse_output_mode(const std::string& name, OutputMode* out) {
  for (int i = 0; i < 6; ++i) {
    if (name == kModeNames[i]) return *out = OutputMode(i), Status::Ok();
  }
  if (name == "ndjson") return *out = OutputMode::kJsonl, Status::Ok();
  return Status::InvalidArgument("unknown output mode '" + name +
                                 "' (text, table, json, jsonl, csv or tsv)");
}

const char* output_mode_name(OutputMode m) { return kModeNames[int(m)]; }

Cell Cell::number(double v) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return {Kind::kNumber, std::string(buf, r.ptr), {}};
}

Cell Cell::number(float v) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return {Kind::kNumber, std::string(buf, r.ptr), {}};
}

std::string plain_text(const Cell& c) {
  switch (c.kind) {
    case Cell::Kind::kNull: return "";
    case Cell::Kind::kList: {
      std::string s;
      for (const std::string& i : c.items) s += (s.empty() ? "" : " ") + i;
      return s;
    }
    default: return c.text;
  }
}

namespace {

std::string json_object(const Table& t, const std::vector<Cell>& row) {
  std::string s = "{";
  for (size_t i = 0; i < row.size(); ++i) {
    s += (i ? ", " : "") + json_string(t.columns[i]) + ": " + json_text(row[i]);
  }
  return s + "}";
}

// One document: the one row of a single answer as an object, any other
// answer as an array, a row a line as sqlite3 prints it.
void print_json(const Table& t, std::FILE* out) {
  if (t.one && t.rows.size() == 1) {
    std::fprintf(out, "%s\n", json_object(t, t.rows[0]).c_str());
    return;
  }
  std::fputs("[", out);
  for (size_t r = 0; r < t.rows.size(); ++r) {
    std::fprintf(out, "%s%s", r ? ",\n" : "", json_object(t, t.rows[r]).c_str());
  }
  std::fputs("]\n", out);
}

void print_json_lines(const Table& t, std::FILE* out) {
  for (const auto& row : t.rows) std::fprintf(out, "%s\n", json_object(t, row).c_str());
}

void print_separated_row(const std::vector<Cell>& row, char sep, std::FILE* out) {
  std::string line;
  for (size_t i = 0; i < row.size(); ++i) {
    line += (i ? std::string(1, sep) : "") + csv_text(row[i], sep);
  }
  std::fprintf(out, "%s\n", line.c_str());
}

void print_separated_header(const std::vector<std::string>& columns, char sep, std::FILE* out) {
  std::vector<Cell> names;
  for (const std::string& c : columns) names.push_back(Cell::string(c));
  if (!names.empty()) print_separated_row(names, sep, out);
}

void print_separated(const Table& t, char sep, std::FILE* out) {
  print_separated_header(t.columns, sep, out);
  for (const auto& row : t.rows) print_separated_row(row, sep, out);
}

// Numbers right-aligned, text left-aligned, as the sqlite3 shell's table mode.
void print_aligned(const Table& t, std::FILE* out) {
  std::vector<size_t> width(t.columns.size());
  for (size_t i = 0; i < t.columns.size(); ++i) width[i] = t.columns[i].size();
  for (const auto& row : t.rows) {
    for (size_t i = 0; i < row.size(); ++i)
      width[i] = std::max(width[i], plain_text(row[i]).size());
  }
  auto line = [&](const std::vector<std::string>& cells, const std::vector<bool>& right) {
    std::string s;
    for (size_t i = 0; i < cells.size(); ++i) {
      const std::string pad(width[i] - cells[i].size(), ' ');
      s += (i ? "  " : "") +
           (right[i] ? pad + cells[i] : cells[i] + (i + 1 < cells.size() ? pad : ""));
    }
    std::fprintf(out, "%s\n", s.c_str());
  };
  line(t.columns, std::vector<bool>(t.columns.size(), false));
  std::vector<std::string> rule;
  for (size_t w : width) rule.push_back(std::string(w, '-'));
  line(rule, std::vector<bool>(width.size(), false));
  for (const auto& row : t.rows) {
    std::vector<std::string> cells;
    std::vector<bool> right;
    for (const Cell& c : row) {
      cells.push_back(plain_text(c));
      right.push_back(c.kind == Cell::Kind::kNumber);
    }
    line(cells, right);
  }
}

}  // namespace

std::string json_text(const Cell& c) {
  switch (c.kind) {
    case Cell::Kind::kNull: return "null";
    case Cell::Kind::kNumber: return c.text;
    case Cell::Kind::kString: return json_string(c.text);
    case Cell::Kind::kList: {
      std::string s = "[";
      for (size_t i = 0; i < c.items.size(); ++i) s += (i ? ", " : "") + c.items[i];
      return s + "]";
    }
  }
  return "null";
}

std::string csv_text(const Cell& c, char separator) {
  const std::string s = plain_text(c);
  if (s.find_first_of(std::string("\"\n\r") + separator) == std::string::npos) return s;
  if (separator == '\t') return s;  // tsv has no quoting; fields hold no tabs here
  std::string q = "\"";
  for (char ch : s) q += ch == '"' ? std::string("\"\"") : std::string(1, ch);
  return q + "\"";
}

void print_table(const Table& t, OutputMode mode, std::FILE* out) {
  switch (mode) {
    case OutputMode::kJson: return print_json(t, out);
    case OutputMode::kJsonl: return print_json_lines(t, out);
    case OutputMode::kCsv: return print_separated(t, ',', out);
    case OutputMode::kTsv: return print_separated(t, '\t', out);
    default: return print_aligned(t, out);
  }
}

TableStream::TableStream(OutputMode mode, std::vector<std::string> columns, std::FILE* out)
    : mode_(mode), out_(out) {
  held_.columns = std::move(columns);
  if (mode_ == OutputMode::kCsv || mode_ == OutputMode::kTsv) {
    print_separated_header(held_.columns, mode_ == OutputMode::kCsv ? ',' : '\t', out_);
  }
}

void TableStream::row(std::vector<Cell> cells) {
  switch (mode_) {
    case OutputMode::kJson:
      std::fprintf(out_, "%s%s", rows_ ? ",\n" : "[", json_object(held_, cells).c_str());
      break;
    case OutputMode::kJsonl: std::fprintf(out_, "%s\n", json_object(held_, cells).c_str()); break;
    case OutputMode::kCsv: print_separated_row(cells, ',', out_); break;
    case OutputMode::kTsv: print_separated_row(cells, '\t', out_); break;
    default: held_.rows.push_back(std::move(cells));
  }
  ++rows_;
}

void TableStream::finish() {
  if (mode_ == OutputMode::kJson) std::fputs(rows_ ? "]\n" : "[]\n", out_);
  if (mode_ == OutputMode::kText || mode_ == OutputMode::kTable) print_aligned(held_, out_);
}

}  // namespace weaver::cli
