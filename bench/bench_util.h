// Shared benchmark plumbing: run a workload in a forked child (so peak RSS is
// the workload's own), collect its JSON line through a pipe, and print a
// table at the end.
#pragma once

#include <fcntl.h>
#include <malloc.h>
#include <sched.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <string>
#include <vector>

namespace weaver::bench {

inline double now_seconds() {
  using clock = std::chrono::steady_clock;
  return std::chrono::duration<double>(clock::now().time_since_epoch()).count();
}

inline uint64_t peak_rss_bytes() {
  struct rusage ru;
  getrusage(RUSAGE_SELF, &ru);
  return static_cast<uint64_t>(ru.ru_maxrss) * 1024;
}

// The median of a sample (the upper one for an even count).
inline double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// A number for a table cell, four significant digits.
inline std::string fmt(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", v);
  return buf;
}

// A flat JSON object built field by field, in insertion order.
class Json {
 public:
  Json& add(const std::string& k, const std::string& v) {
    fields_.emplace_back(k, "\"" + v + "\"");
    return *this;
  }
  Json& add(const std::string& k, const char* v) { return add(k, std::string(v)); }
  Json& add(const std::string& k, double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.6g", v);
    fields_.emplace_back(k, buf);
    return *this;
  }
  Json& add(const std::string& k, uint64_t v) {
    fields_.emplace_back(k, std::to_string(v));
    return *this;
  }
  Json& add(const std::string& k, int v) { return add(k, static_cast<uint64_t>(v)); }
  std::string str() const {
    std::string s = "{";
    for (size_t i = 0; i < fields_.size(); ++i) {
      if (i) s += ", ";
      s += "\"" + fields_[i].first + "\": " + fields_[i].second;
    }
    return s + "}";
  }
  // The raw text of a field ("" if absent), for the table.
  std::string get(const std::string& k) const {
    for (const auto& f : fields_) {
      if (f.first == k) return f.second;
    }
    return "";
  }

 private:
  std::vector<std::pair<std::string, std::string>> fields_;
};

// Reads the child's end of the pipe to EOF, then reaps the child; returns
// its output, or "" if it failed.  Sets *peak_rss (may be null).
inline std::string collect_child(pid_t pid, int read_fd, uint64_t* peak_rss) {
  std::string text;
  char buf[4096];
  ssize_t r;
  while ((r = read(read_fd, buf, sizeof buf)) > 0) text.append(buf, static_cast<size_t>(r));
  close(read_fd);
  int status = 0;
  struct rusage ru;
  wait4(pid, &status, 0, &ru);
  if (peak_rss != nullptr) *peak_rss = static_cast<uint64_t>(ru.ru_maxrss) * 1024;
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    std::fprintf(stderr, "child failed: %s\n", text.c_str());
    return "";
  }
  return text;
}

// Restricts this process, and the threads and programs it starts after, to
// the first CPU it may run on: the one-core baseline of a speedup, whatever
// helper threads the stage starts.  False if the kernel refuses.
inline bool pin_to_one_core() {
  cpu_set_t allowed;
  if (sched_getaffinity(0, sizeof allowed, &allowed) != 0) return false;
  for (int c = 0; c < CPU_SETSIZE; ++c) {
    if (!CPU_ISSET(c, &allowed)) continue;
    cpu_set_t one;
    CPU_ZERO(&one);
    CPU_SET(c, &one);
    return sched_setaffinity(0, sizeof one, &one) == 0;
  }
  return false;
}

// Runs fn in a child process and returns its JSON line (with peak_rss_bytes
// added), or "" if the child failed.
inline std::string run_in_child(const std::function<bool(Json*)>& fn) {
  int fds[2];
  if (pipe(fds) != 0) return "";
  std::fflush(stdout);
  const pid_t pid = fork();
  if (pid == 0) {
    close(fds[0]);
    Json j;
    const bool ok = fn(&j);
    j.add("peak_rss_bytes", peak_rss_bytes());
    const std::string s = j.str();
    if (write(fds[1], s.data(), s.size()) != static_cast<ssize_t>(s.size())) _exit(2);
    _exit(ok ? 0 : 1);
  }
  close(fds[1]);
  return collect_child(pid, fds[0], nullptr);
}

// Runs argv[0] (a path) with its arguments in a fresh process, returning its
// stdout ("" on failure) and its peak RSS.  A fresh process, not a fork of
// this one: a fork inherits this process's heap, and copy-on-write faults
// then distort a multi-threaded child's timing.
// With out_path, the program's stdout goes to that file (as a user's shell
// redirect would) and the result is "ok" on success.  With one_core, it
// runs on one CPU (pin_to_one_core).
inline std::string run_program(const std::vector<std::string>& args, uint64_t* peak_rss,
                               const std::string& out_path = "", bool one_core = false) {
  int fds[2];
  if (pipe(fds) != 0) return "";
  std::fflush(stdout);
  // A forked child starts with the RSS this process has at the fork, and a
  // child's peak counts it; return freed heap first, so that the peak of a
  // program run from a test that used much memory before is its own.
  malloc_trim(0);
  const pid_t pid = fork();
  if (pid == 0) {
    const int out =
        out_path.empty() ? fds[1] : ::open(out_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (out < 0) _exit(126);
    dup2(out, STDOUT_FILENO);
    if (!out_path.empty()) ::write(fds[1], "ok", 2), close(out);
    close(fds[0]);
    close(fds[1]);
    if (one_core && !pin_to_one_core()) _exit(126);
    std::vector<char*> argv;
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    execv(argv[0], argv.data());
    _exit(127);
  }
  close(fds[1]);
  return collect_child(pid, fds[0], peak_rss);
}

// "0.5,1,2" as numbers (a --freq list).
inline std::vector<double> number_list(const std::string& text) {
  std::vector<double> out;
  size_t at = 0;
  while (at <= text.size()) {
    const size_t comma = std::min(text.find(',', at), text.size());
    out.push_back(std::stod(text.substr(at, comma - at)));
    at = comma + 1;
  }
  return out;
}

// The file of db's octant table (its first, for a sharded one).
inline std::string octant_table(const std::string& db) {
  for (const auto& e : std::filesystem::directory_iterator(db)) {
    if (e.path().filename().string().rfind("octants-", 0) == 0) return e.path().string();
  }
  return "";
}

// Whether two files hold the same bytes.
inline bool same_bytes(const std::string& a, const std::string& b) {
  std::ifstream fa(a, std::ios::binary), fb(b, std::ios::binary);
  std::vector<char> x(1 << 20), y(1 << 20);
  while (fa && fb) {
    fa.read(x.data(), x.size());
    fb.read(y.data(), y.size());
    if (fa.gcount() != fb.gcount() || !std::equal(x.begin(), x.begin() + fa.gcount(), y.begin()))
      return false;
  }
  return !fa && !fb;
}

// Parses the flat objects Json::str() writes: {"k": value, ...}.
// Drops the files under dir from the kernel's page cache (after writing
// back what is dirty), so that the next run reads them from disk: --cold.
inline void drop_page_cache(const std::string& dir) {
  ::sync();
  std::error_code ec;
  for (const auto& e : std::filesystem::recursive_directory_iterator(dir, ec)) {
    if (!e.is_regular_file()) continue;
    const int fd = ::open(e.path().c_str(), O_RDONLY);
    if (fd < 0) continue;
    ::posix_fadvise(fd, 0, 0, POSIX_FADV_DONTNEED);
    ::close(fd);
  }
}

inline std::map<std::string, std::string> parse_flat_json(const std::string& s) {
  std::map<std::string, std::string> out;
  size_t i = 0;
  while ((i = s.find('"', i)) != std::string::npos) {
    const size_t kend = s.find('"', i + 1);
    const std::string key = s.substr(i + 1, kend - i - 1);
    size_t v = s.find(':', kend) + 1;
    while (s[v] == ' ') ++v;
    size_t vend;
    if (s[v] == '"') {
      vend = s.find('"', v + 1) + 1;
      out[key] = s.substr(v + 1, vend - v - 2);
    } else {
      vend = s.find_first_of(",}", v);
      out[key] = s.substr(v, vend - v);
    }
    i = vend;
  }
  return out;
}

// Prints rows as an aligned text table with the given columns.
inline void print_table(const std::vector<std::map<std::string, std::string>>& rows,
                        const std::vector<std::string>& columns) {
  std::vector<size_t> width(columns.size());
  for (size_t c = 0; c < columns.size(); ++c) {
    width[c] = columns[c].size();
    for (const auto& r : rows) {
      auto it = r.find(columns[c]);
      if (it != r.end()) width[c] = std::max(width[c], it->second.size());
    }
  }
  for (size_t c = 0; c < columns.size(); ++c)
    std::printf("%-*s  ", int(width[c]), columns[c].c_str());
  std::printf("\n");
  for (const auto& r : rows) {
    for (size_t c = 0; c < columns.size(); ++c) {
      auto it = r.find(columns[c]);
      std::printf("%-*s  ", int(width[c]), it == r.end() ? "" : it->second.c_str());
    }
    std::printf("\n");
  }
}

}  // namespace weaver::bench
