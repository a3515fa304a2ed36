// weaver shell DB: an interactive prompt over one open database, in the
// manner of the sqlite3 shell.  Every `weaver query` works as a command;
// dot commands set the output, time commands, read scripts and reload.
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <iostream>
#include <sstream>

#include "cli/cli.h"
#include "cli/line_editor.h"
#include "cli/query_commands.h"
#include "util/interrupt.h"

namespace weaver::cli {
namespace {

constexpr char kUsage[] =
    "usage: weaver shell DB [--memory BYTES]\n"
    "\n"
    "An interactive prompt over the mesh in DB, opened once, read-only. Type any\n"
    "'weaver query' question without 'weaver query DB' (locate 1 2 3, neighbors 7\n"
    "--all), or a dot command (.help). Lines from a pipe or file are run one by one,\n"
    "so scripts can drive it: the exit status is 1 if any command failed.\n"
    "  --memory BYTES  memory budget (default 256M)\n";

constexpr char kDotHelp[] =
    ".help                 this text\n"
    ".mode [MODE]          output mode: text (default), table, json, jsonl, csv or tsv\n"
    ".timer on|off         print the wall time of each command\n"
    ".units ticks|m        coordinates in and out in ticks (default) or metres\n"
    ".read FILE            run the commands in FILE\n"
    ".reload               reopen the database at its newest commit\n"
    ".show                 the database, its counts and the settings\n"
    ".quit                 leave (also .exit, or Ctrl-D)\n"
    "A query with --points - reads its points from the lines that follow it, up to a\n"
    "line holding only \".\" (or the end of the input).\n"
    "Queries:\n";

// Splits a line into words at blanks; "double" or 'single' quotes keep
// blanks inside a word (a file name with spaces).
std::vector<std::string> words_of(const std::string& line) {
  std::vector<std::string> out;
  std::string w;
  bool in_word = false;
  char quote = 0;
  for (const char c : line) {
    if (quote != 0) {
      if (c == quote) {
        quote = 0;
      } else {
        w += c;
      }
    } else if (c == '"' || c == '\'') {
      quote = c, in_word = true;
    } else if (c == ' ' || c == '\t' || c == '\r') {
      if (in_word) out.push_back(w), w.clear(), in_word = false;
    } else {
      w += c, in_word = true;
    }
  }
  if (in_word) out.push_back(w);
  return out;
}

class Shell {
 public:
  Shell(std::string db, MemoryBudget memory, std::string memory_text)
      : db_(std::move(db)), memory_(memory), memory_text_(std::move(memory_text)) {}

  // A model database (no mesh) answers 'material' from its model table.
  Status open() {
    model_only_ = is_model_only(db_);
    return model_only_ ? Status::Ok() : Explorer::open(db_, memory_, &ex_);
  }
  bool failed() const { return failed_; }

  // Gives the next line of the input the current line came from; false at its end.
  using NextLine = std::function<bool(std::string*)>;

  // Runs one line; false when it asks to leave.  A query reading
  // `--points -` takes the lines after it from next, up to ".".
  bool line(const std::string& text, const NextLine& next) {
    const std::vector<std::string> w = words_of(text);
    if (w.empty() || w[0][0] == '#') return true;
    const auto t0 = std::chrono::steady_clock::now();
    bool go_on = true;
    if (w[0][0] == '.') {
      go_on = dot(w);
    } else if (model_only_) {
      std::fflush(stdout);
      failed_ |= query_model(db_, w, memory_text_) != 0;
    } else if (reads_points_from_input(w)) {
      query_with_inline_points(w, next);
    } else {
      std::fflush(stdout);
      failed_ |= run_query(*ex_, w, settings_, stdout, stderr, "error") != 0;
    }
    if (timer_) {
      const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      std::printf("Run Time: real %.6f\n", s);
    }
    std::fflush(stdout);
    return go_on;
  }

  // Runs every line of in; false when one asks to leave.
  bool lines(std::istream& in) {
    const NextLine next = [&in](std::string* l) { return bool(std::getline(in, *l)); };
    for (std::string text; std::getline(in, text);) {
      if (!line(text, next)) return false;
    }
    return true;
  }

  void banner() const {
    if (model_only_) {
      std::printf("weaver shell: %s, a model database (read-only): 'material X Y Z' in metres\n",
                  db_.c_str());
      std::printf("Enter \".help\" for usage hints.\n");
      return;
    }
    std::printf("weaver shell: %s, %llu elements, %llu nodes (read-only)\n", db_.c_str(),
                (unsigned long long)ex_->element_count(), (unsigned long long)ex_->node_count());
    std::printf("Enter \".help\" for usage hints.\n");
  }

 private:
  void error(const std::string& message) {
    std::fflush(stdout);
    std::fprintf(stderr, "error: %s\n", message.c_str());
    failed_ = true;
  }

  static bool reads_points_from_input(const std::vector<std::string>& w) {
    for (size_t i = 1; i + 1 < w.size(); ++i) {
      if (w[i] == "--points" && w[i + 1] == "-") return true;
    }
    return false;
  }

  // The points are gathered in memory and read from there as the query's
  // stdin: the shell's own input goes on after the ".".
  void query_with_inline_points(const std::vector<std::string>& w, const NextLine& next) {
    std::string points;
    for (std::string l; next(&l) && l != ".";) points += l + "\n";
    if (points.empty()) points = "\n";  // fmemopen needs a byte; a blank line is no point
    std::FILE* in = fmemopen(points.data(), points.size(), "r");
    if (in == nullptr) return error(std::string("cannot read the points: ") + std::strerror(errno));
    QuerySettings with_points = settings_;
    with_points.points_stdin = in;
    std::fflush(stdout);
    failed_ |= run_query(*ex_, w, with_points, stdout, stderr, "error") != 0;
    std::fclose(in);
  }

  bool on_off(const std::vector<std::string>& w, bool* flag) {
    if (w.size() == 2 && (w[1] == "on" || w[1] == "off")) return *flag = w[1] == "on", true;
    error(w[0] + " takes on or off");
    return true;
  }

  bool dot(const std::vector<std::string>& w) {
    const std::string& c = w[0];
    if (c == ".quit" || c == ".exit") return false;
    if (c == ".help") return std::printf("%s%s", kDotHelp, kQueryHelp), true;
    if (c == ".timer") return on_off(w, &timer_);
    if (c == ".mode") return mode(w);
    if (c == ".units") return units(w);
    if (c == ".read") return read(w);
    if (c == ".reload") return reload();
    if (c == ".show") return show();
    error("unknown command '" + c + "' (see .help)");
    return true;
  }

  bool mode(const std::vector<std::string>& w) {
    if (w.size() == 1) return std::printf("%s\n", output_mode_name(settings_.mode)), true;
    const Status st = w.size() == 2 ? parse_output_mode(w[1], &settings_.mode)
                                    : Status::InvalidArgument(".mode takes one mode");
    if (!st.ok()) error(st.message());
    return true;
  }

  bool units(const std::vector<std::string>& w) {
    if (w.size() == 2 && (w[1] == "ticks" || w[1] == "m")) {
      settings_.metres = w[1] == "m";
    } else {
      error(".units takes ticks or m");
    }
    return true;
  }

  bool read(const std::vector<std::string>& w) {
    if (w.size() != 2) return error(".read takes a file"), true;
    if (++depth_ > 16) return --depth_, error(".read nested too deeply"), true;
    std::ifstream in(w[1]);
    bool go_on = true;
    if (!in) {
      error("cannot open " + w[1] + ": " + std::strerror(errno));
    } else {
      go_on = lines(in);
    }
    --depth_;
    return go_on;
  }

  bool reload() {
    std::unique_ptr<Explorer> fresh;
    const Status st = Explorer::open(db_, memory_, &fresh);
    if (!st.ok()) return error(error_text(st) + " (still on the old snapshot)"), true;
    ex_ = std::move(fresh);
    std::printf("reloaded: %llu elements, %llu nodes\n", (unsigned long long)ex_->element_count(),
                (unsigned long long)ex_->node_count());
    return true;
  }

  bool show() const {
    std::printf(
        "database: %s\nelements: %llu\nnodes:    %llu\nmaterial: %s\nmode:     %s\n"
        "units:    %s (1 tick = %g m)\ntimer:    %s\n",
        db_.c_str(), (unsigned long long)ex_->element_count(),
        (unsigned long long)ex_->node_count(), ex_->mesh().has_material() ? "yes" : "no",
        output_mode_name(settings_.mode), settings_.metres ? "m" : "ticks", ex_->units().tick_m,
        timer_ ? "on" : "off");
    return true;
  }

  std::string db_;
  MemoryBudget memory_;
  std::string memory_text_;  // --memory as given, for a model database's queries
  bool model_only_ = false;
  std::unique_ptr<Explorer> ex_;
  QuerySettings settings_;
  bool timer_ = false;
  bool failed_ = false;
  int depth_ = 0;
};

std::string history_path() {
  const char* home = std::getenv("HOME");
  return home != nullptr && *home != '\0' ? std::string(home) + "/.weaver_history" : "";
}

}  // namespace

int cmd_shell(int argc, char** argv) {
  ParsedArgs args;
  Status st = parse_args(argc, argv, 2, {"memory"}, {}, &args);
  if (args.help) return std::fputs(kUsage, stdout), 0;
  if (!st.ok()) return usage_error("shell", st.message(), kUsage);
  if (args.positional.size() != 1) return usage_error("shell", "expected DB", kUsage);
  MemoryBudget memory;
  st = memory_option(args, &memory);
  if (!st.ok()) return usage_error("shell", st.message(), kUsage);
  Shell shell(args.positional[0], memory,
              args.values.count("memory") ? args.values.at("memory") : "");
  st = shell.open();
  if (!st.ok()) return report("shell", st);
  if (!isatty(STDIN_FILENO) || !isatty(STDOUT_FILENO)) {
    shell.lines(std::cin);
    return shell.failed() ? 1 : 0;
  }
  shell.banner();
  // Ctrl-C ends the question being answered, not the shell.
  InterruptScope ctrl_c;
  LineEditor editor;
  const std::string history = history_path();
  if (!history.empty()) editor.load_history(history);
  const Shell::NextLine more = [&editor](std::string* l) { return editor.read("   ...> ", l); };
  for (std::string line; editor.read("weaver> ", &line);) {
    editor.remember(line);
    clear_interrupt();
    if (!shell.line(line, more)) break;
  }
  if (!history.empty()) editor.save_history(history);
  return 0;
}

}  // namespace weaver::cli
