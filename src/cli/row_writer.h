// The rows of a points batch (`weaver query ... --points`, `weaver serve`'s
// POST /api/points): text, table, csv, tsv, JSON or JSON lines, written into
// a buffer flushed to the output in large writes.  A million rows a second is
// too many for a printf each, and too many for a writer whose every field
// stores a byte and then reloads the writer's own state (a char store may
// alias it): a row is written through a RowCursor, whose position lives in a
// register until the row ends.
#pragma once

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "cli/query_output.h"
#include "schema/status.h"
#include "util/short_decimal.h"

namespace weaver::cli {

// How a row's fields are set apart: the same for every row of a document.
struct RowStyle {
  OutputMode mode = OutputMode::kText;
  bool json = false;  // JSON or JSON lines: each field with its column's name
  char separator = ' ';
  std::string_view null;                // a field with no value
  std::vector<std::string_view> names;  // the columns (lengths found once)

  explicit RowStyle(OutputMode m)
      : mode(m),
        json(m == OutputMode::kJson || m == OutputMode::kJsonl),
        separator(m == OutputMode::kCsv   ? ','
                  : m == OutputMode::kTsv ? '\t'
                                          : ' '),
        null(json                     ? "null"
             : m == OutputMode::kText ? "-"
                                      : "") {}
};

// Writes one row's fields from p on; the caller made room for the longest
// row.  Fields go in the order of the style's names.
class RowCursor {
 public:
  RowCursor(char* at, const RowStyle& style) : p_(at), s_(style) {}
  template <typename T>
  void number(T v) {
    lead(false);
    if constexpr (std::is_floating_point_v<T>) {
      p_ = write_short_decimal(p_, v);
    } else {
      p_ = std::to_chars(p_, p_ + 40, v).ptr;
    }
    ++field_;
  }
  void text(std::string_view v) {
    lead(true);
    copy(v);
    if (s_.json) *p_++ = '"';
    ++field_;
  }
  void null() {
    lead(false);
    copy(s_.null);
    ++field_;
  }
  // Ends the row; returns where the next one starts.
  char* end() {
    copy(s_.mode == OutputMode::kJson ? "}" : s_.json ? "}\n" : "\n");
    return p_;
  }

 private:
  // What goes before a field: a separator, or in JSON its name.
  void lead(bool quoted) {
    if (s_.json) {
      copy(field_ == 0 ? "{\"" : ", \"");
      copy(s_.names[field_]);
      copy(quoted ? "\": \"" : "\": ");
    } else if (field_ > 0) {
      *p_++ = s_.separator;
    }
  }
  void copy(std::string_view v) {
    std::memcpy(p_, v.data(), v.size());
    p_ += v.size();
  }

  char* p_;
  const RowStyle& s_;
  size_t field_ = 0;
};

// The buffer the rows go into, and what a document puts around them.
class RowWriter {
 public:
  // A row's longest: 13 fields with their JSON names, and margin.
  static constexpr size_t kMaxRow = 2048;

  // one: the answer to one point, which JSON prints as an object rather
  // than as an array of one.
  RowWriter(OutputMode mode, bool one) : style_(mode), one_(one) { reserve(kCapacity); }
  RowWriter(RowWriter&&) = default;

  void header(const std::vector<const char*>& columns) {
    style_.names.assign(columns.begin(), columns.end());
    if (style_.mode == OutputMode::kJson && !one_) raw("[");
    if (style_.json) return;
    if (style_.mode == OutputMode::kText || style_.mode == OutputMode::kTable) raw("# ");
    RowCursor c(row(), style_);
    for (const char* name : columns) c.text(name);
    done(c.end());
  }
  // A row starts here: room for the longest row is made first.
  char* row() {
    if (len_ + kMaxRow > cap_) reserve(std::max(cap_ * 2, len_ + kMaxRow));
    if (style_.mode == OutputMode::kJson && rows_ > 0) raw(",\n");
    return &buf_[len_];
  }
  // The row that started at row() ends at `at`.
  void done(char* at) {
    len_ = size_t(at - buf_.get());
    ++rows_;
  }
  const RowStyle& style() const { return style_; }
  // After the last row: closes the JSON document.
  void close_document() {
    if (len_ + 4 > cap_) reserve(len_ + 4);
    if (style_.mode == OutputMode::kJson) raw(one_ && rows_ == 1 ? "\n" : "]\n");
  }
  // A writer of the same columns for rows that follow `rows` rows of this
  // document, into a buffer of its own: a slice formatted on another
  // thread, written after those.
  RowWriter continuation(uint64_t rows) const {
    RowWriter w(style_.mode, one_);
    w.style_ = style_;
    w.rows_ = rows;
    return w;
  }
  uint64_t rows() const { return rows_; }
  // Forgets the rows held (they were written) and goes on after `rows` rows.
  void resume(uint64_t rows) { rows_ = rows, len_ = 0; }
  // Rows written by continuations count as this writer's.
  void count_rows(uint64_t n) { rows_ += n; }
  // Writes the rows held to out and forgets them.
  Status flush(std::FILE* out) {
    if (len_ > 0 && std::fwrite(buf_.get(), 1, len_, out) != len_) {
      return Status::IOError(std::string("writing the answers: ") + std::strerror(errno));
    }
    len_ = 0;
    return Status::Ok();
  }

 private:
  // Where the buffer starts: it doubles as rows need (a batch's slice of
  // rows fills about a megabyte), while one point's answer, asked a thousand
  // times a second through `weaver serve`, never zeroes a megabyte.
  static constexpr size_t kCapacity = 16 << 10;

  // Room for n bytes, the bytes held kept; new room is not zeroed (a batch's
  // rows fill megabytes, written over at once).
  void reserve(size_t n) {
    std::unique_ptr<char[]> bigger(new char[n]);
    if (len_ > 0) std::memcpy(bigger.get(), buf_.get(), len_);
    buf_ = std::move(bigger);
    cap_ = n;
  }
  void raw(std::string_view v) {
    std::memcpy(&buf_[len_], v.data(), v.size());
    len_ += v.size();
  }

  RowStyle style_;
  bool one_;
  uint64_t rows_ = 0;
  std::unique_ptr<char[]> buf_;
  size_t cap_ = 0, len_ = 0;
};

}  // namespace weaver::cli
