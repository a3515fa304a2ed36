#include "cli/line_editor.h"

#include <errno.h>
#include <termios.h>
#include <unistd.h>

#include <fstream>

namespace weaver::cli {
namespace {

constexpr size_t kMaxHistory = 1000;

// Raw mode for the life of a read: bytes as typed, no echo, no line
// discipline; restored whatever happens.
class RawMode {
 public:
  explicit RawMode(int fd) : fd_(fd) {
    if (tcgetattr(fd, &saved_) != 0) return;
    termios raw = saved_;
    raw.c_iflag &= ~(BRKINT | ICRNL | INPCK | ISTRIP | IXON);
    raw.c_oflag &= ~OPOST;
    raw.c_cflag |= CS8;
    raw.c_lflag &= ~(ECHO | ICANON | IEXTEN | ISIG);
    raw.c_cc[VMIN] = 1;
    raw.c_cc[VTIME] = 0;
    ok_ = tcsetattr(fd, TCSANOW, &raw) == 0;  // TCSANOW: keep what was typed ahead
  }
  ~RawMode() {
    if (ok_) tcsetattr(fd_, TCSANOW, &saved_);
  }
  bool ok() const { return ok_; }

 private:
  int fd_;
  termios saved_{};
  bool ok_ = false;
};

}  // namespace

void LineEditor::put(const std::string& s) const {
  size_t done = 0;
  while (done < s.size()) {
    const ssize_t n = ::write(out_, s.data() + done, s.size() - done);
    if (n < 0 && errno == EINTR) continue;  // Ctrl-C (the shell's handler) mid-write
    if (n <= 0) return;
    done += size_t(n);
  }
}

void LineEditor::refresh() {
  // Back to the start of the line, prompt and text, clear the rest, then
  // put the cursor back where it belongs.
  std::string s = "\r" + prompt_ + buf_ + "\x1b[K\r";
  const size_t column = prompt_.size() + pos_;
  if (column > 0) s += "\x1b[" + std::to_string(column) + "C";
  put(s);
}

void LineEditor::recall(int step) {
  if (history_.empty()) return;
  if (recalled_ == history_.size()) edited_ = buf_;
  if (step < 0 && recalled_ > 0) --recalled_;
  if (step > 0 && recalled_ < history_.size()) ++recalled_;
  buf_ = recalled_ == history_.size() ? edited_ : history_[recalled_];
  pos_ = buf_.size();
}

void LineEditor::escape() {
  char seq[3] = {0, 0, 0};
  if (::read(in_, &seq[0], 1) != 1 || ::read(in_, &seq[1], 1) != 1) return;
  if (seq[0] != '[' && seq[0] != 'O') return;
  if (seq[1] >= '0' && seq[1] <= '9') {  // ESC [ n ~
    if (::read(in_, &seq[2], 1) != 1 || seq[2] != '~') return;
    if (seq[1] == '3' && pos_ < buf_.size()) buf_.erase(pos_, 1);
    if (seq[1] == '1' || seq[1] == '7') pos_ = 0;
    if (seq[1] == '4' || seq[1] == '8') pos_ = buf_.size();
    return;
  }
  switch (seq[1]) {
    case 'A': return recall(-1);
    case 'B': return recall(+1);
    case 'C': pos_ += pos_ < buf_.size(); return;
    case 'D': pos_ -= pos_ > 0; return;
    case 'H': pos_ = 0; return;
    case 'F': pos_ = buf_.size(); return;
  }
}

LineEditor::Key LineEditor::key(char c) {
  switch (c) {
    case '\r':
    case '\n': return Key::kEnter;
    case 3: return Key::kCancel;  // Ctrl-C
    case 4:                       // Ctrl-D
      if (buf_.empty()) return Key::kEof;
      if (pos_ < buf_.size()) buf_.erase(pos_, 1);
      break;
    case 127:
    case 8:  // Backspace
      if (pos_ > 0) buf_.erase(--pos_, 1);
      break;
    case 1: pos_ = 0; break;                        // Ctrl-A
    case 5: pos_ = buf_.size(); break;              // Ctrl-E
    case 2: pos_ -= pos_ > 0; break;                // Ctrl-B
    case 6: pos_ += pos_ < buf_.size(); break;      // Ctrl-F
    case 11: buf_.erase(pos_); break;               // Ctrl-K
    case 21: buf_.erase(0, pos_), pos_ = 0; break;  // Ctrl-U
    case 23: {                                      // Ctrl-W
      size_t start = pos_;
      while (start > 0 && buf_[start - 1] == ' ') --start;
      while (start > 0 && buf_[start - 1] != ' ') --start;
      buf_.erase(start, pos_ - start), pos_ = start;
      break;
    }
    case 16: recall(-1); break;            // Ctrl-P
    case 14: recall(+1); break;            // Ctrl-N
    case 12: put("\x1b[H\x1b[2J"); break;  // Ctrl-L
    case 27: escape(); break;
    default:
      if (static_cast<unsigned char>(c) >= 32) buf_.insert(pos_++, 1, c);
  }
  return Key::kNone;
}

bool LineEditor::read(const std::string& prompt, std::string* line) {
  prompt_ = prompt;
  buf_.clear();
  pos_ = 0;
  recalled_ = history_.size();
  RawMode raw(in_);
  if (!raw.ok()) return false;
  refresh();
  for (;;) {
    char c = 0;
    if (::read(in_, &c, 1) != 1) return put("\r\n"), false;
    const Key k = key(c);
    if (k == Key::kEof) return put("\r\n"), false;
    if (k == Key::kCancel) {
      put("^C\r\n");
      buf_.clear(), pos_ = 0;
    }
    if (k == Key::kEnter) {
      put("\r\n");
      *line = buf_;
      return true;
    }
    refresh();
  }
}

void LineEditor::remember(const std::string& line) {
  if (line.find_first_not_of(" \t") == std::string::npos) return;
  if (!history_.empty() && history_.back() == line) return;
  history_.push_back(line);
  if (history_.size() > kMaxHistory) history_.erase(history_.begin());
}

void LineEditor::load_history(const std::string& path) {
  std::ifstream in(path);
  for (std::string line; std::getline(in, line);) remember(line);
}

void LineEditor::save_history(const std::string& path) const {
  std::ofstream out(path, std::ios::trunc);
  for (const std::string& line : history_) out << line << '\n';
}

}  // namespace weaver::cli
