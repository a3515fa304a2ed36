// A small line editor for the interactive shell, in the manner of linenoise:
// the terminal in raw mode while a line is read, editing keys, and a history
// walked with the arrow keys.  Used only when stdin and stdout are a
// terminal; the shell reads plain lines from a pipe or file.
//
// Keys: left/right (Ctrl-B/F), Home/End (Ctrl-A/E), Backspace, Delete,
// Ctrl-K (kill to end), Ctrl-U (kill to start), Ctrl-W (kill a word),
// up/down (Ctrl-P/N) through the history, Ctrl-L (clear screen), Ctrl-C
// (drop the line), Ctrl-D (end of input on an empty line).
#pragma once

#include <string>
#include <vector>

namespace weaver::cli {

class LineEditor {
 public:
  explicit LineEditor(int in_fd = 0, int out_fd = 1) : in_(in_fd), out_(out_fd) {}

  // Shows prompt and reads one line into *line; false at end of input
  // (Ctrl-D on an empty line, or the terminal closing).
  bool read(const std::string& prompt, std::string* line);
  // Adds a line to the history (not blanks, not a repeat of the last).
  void remember(const std::string& line);
  const std::vector<std::string>& history() const { return history_; }
  // The history from and to a file, one line each (~/.weaver_history).
  void load_history(const std::string& path);
  void save_history(const std::string& path) const;

 private:
  enum class Key { kNone, kEnter, kEof, kCancel };
  // Applies one key (with escape sequences read in full) to the line.
  Key key(char c);
  void escape();
  void refresh();
  void recall(int step);
  void put(const std::string& s) const;

  int in_, out_;
  std::string prompt_, buf_;
  size_t pos_ = 0;
  std::vector<std::string> history_;
  size_t recalled_ = 0;  // history_.size(): the line being edited
  std::string edited_;   // that line, kept while the history is walked
};

}  // namespace weaver::cli
