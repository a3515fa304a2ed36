// weaver shell driven as users drive it: by a script through a pipe, and
// once through a pseudo-terminal with the line editor's keys.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "cli_run.h"
#include "gen/octree_gen.h"
#include "import/import.h"
#include "import/octant_text.h"
#include "test_mesh.h"

namespace weaver {
namespace {

// A child running `weaver shell db` with stdin and stdout on a pipe pair or
// on a pseudo-terminal.
class ShellProcess {
 public:
  ShellProcess(const std::string& db, bool terminal) {
    int in[2] = {-1, -1}, out[2] = {-1, -1};
    std::string slave;
    if (terminal) {
      master_ = posix_openpt(O_RDWR | O_NOCTTY);
      EXPECT_GE(master_, 0);
      fcntl(master_, F_SETFD, FD_CLOEXEC);  // the shell must not hold the master
      EXPECT_EQ(grantpt(master_), 0);
      EXPECT_EQ(unlockpt(master_), 0);
      slave = ptsname(master_);
    } else {
      EXPECT_EQ(pipe(in), 0);
      EXPECT_EQ(pipe(out), 0);
    }
    pid_ = fork();
    if (pid_ == 0) {
      if (terminal) {
        setsid();
        const int fd = open(slave.c_str(), O_RDWR);
        dup2(fd, 0), dup2(fd, 1), dup2(fd, 2);
      } else {
        dup2(in[0], 0), dup2(out[1], 1), dup2(out[1], 2);
        close(in[1]), close(out[0]);
      }
      setenv("HOME", "/nonexistent-weaver-test-home", 1);
      execl(WEAVER_BINARY, WEAVER_BINARY, "shell", db.c_str(), "--memory", "16M", nullptr);
      _exit(127);
    }
    if (terminal) {
      write_fd_ = read_fd_ = master_;
    } else {
      close(in[0]), close(out[1]);
      write_fd_ = in[1], read_fd_ = out[0];
    }
  }
  ~ShellProcess() {
    if (pid_ > 0) kill(pid_, SIGKILL), waitpid(pid_, nullptr, 0);
  }

  void send(const std::string& s) {
    ASSERT_EQ(write(write_fd_, s.data(), s.size()), ssize_t(s.size()));
  }
  void close_input() {
    if (write_fd_ != read_fd_) close(write_fd_);
  }
  // Reads until `marker` shows up, or the shell has been silent for
  // `idle_rounds` polls of 100 ms; everything read so far.  Only silence
  // counts: an interrupted points file writes megabytes first.
  std::string read_until(const std::string& marker, int idle_rounds = 300) {
    for (int idle = 0; out_.find(marker) == std::string::npos && idle < idle_rounds;) {
      if (!read_some()) ++idle;
    }
    return out_;
  }
  // Reads until a fresh prompt follows `marker` in the output: the shell has
  // answered and waits for keys (the editor redraws its prompt on every key,
  // so prompts cannot be counted).  Sending keys before that would type
  // them ahead into the terminal's line discipline instead of the editor.
  std::string prompt_after(const std::string& marker) {
    for (int idle = 0; idle < 300;) {
      const size_t at = out_.find(marker);
      if (at != std::string::npos && out_.find("weaver> ", at) != std::string::npos) return out_;
      if (!read_some()) ++idle;
    }
    ADD_FAILURE() << "no prompt after \"" << marker << "\" in 30 s of silence";
    return out_;
  }
  // The exit status, or -1 if the shell has not ended within 30 s (it is
  // then killed: a test never hangs on it).
  int wait() {
    int status = 0;
    for (int waited = 0; waited < 1500; ++waited) {
      if (waitpid(pid_, &status, WNOHANG) == pid_) {
        pid_ = -1;
        return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
      }
      read_some();  // keep draining its output meanwhile
      usleep(20000);
    }
    return -1;
  }

 private:
  // One poll of up to 100 ms and what it brings; false if nothing came.
  bool read_some() {
    pollfd p{read_fd_, POLLIN, 0};
    if (poll(&p, 1, 100) <= 0) return false;
    char buf[1 << 16];
    const ssize_t n = read(read_fd_, buf, sizeof buf);
    if (n <= 0) return false;
    out_.append(buf, size_t(n));
    return true;
  }

  pid_t pid_ = -1;
  int master_ = -1, write_fd_ = -1, read_fd_ = -1;
  std::string out_;
};

// Every file of a directory with its size and modification time.
std::string snapshot(const std::string& dir) {
  std::string s;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    s += e.path().filename().string() + " " + std::to_string(e.file_size()) + " " +
         std::to_string(e.last_write_time().time_since_epoch().count()) + "\n";
  }
  return s;
}

TEST(Shell, ScriptThroughAPipeRunsQueriesAndDotCommands) {
  testing::TempDir dir;
  const std::string db = testing::build_mesh(testing::small_sphere(), dir);
  std::ofstream(dir.file("more.txt")) << "# a script read by .read\nnode 0\n";
  const std::string same = testing::run("query " + db + " element 3").out;
  const std::string files = snapshot(db);
  ShellProcess sh(db, false);
  sh.send(
      "element 3\n"
      ".mode csv\n"
      "locate 0 0 0\n"
      ".timer on\n"
      "element 0\n"
      ".timer off\n"
      "frobnicate 1\n"
      ".mode banana\n"
      "element 999999\n"
      ".units m\n"
      ".read " +
      dir.file("more.txt") +
      "\n"
      ".show\n"
      ".quit\n"
      "element 1\n");
  sh.close_input();
  const std::string out = sh.read_until("\x04");  // to the end
  EXPECT_EQ(sh.wait(), 1) << out;                 // some commands failed
  EXPECT_EQ(out.rfind(same, 0), 0u) << "the same output as 'weaver query':\n" << out;
  EXPECT_NE(out.find("x,y,z,status,element,level,edge,corner_x,corner_y,corner_z\n0,0,0,inside,0,"),
            std::string::npos)
      << out;
  EXPECT_NE(out.find("element,x,y,z,level,edge,nodes\n0,0,0,0,"), std::string::npos) << out;
  size_t timers = 0;
  for (size_t at = 0; (at = out.find("Run Time: real ", at)) != std::string::npos; ++at) ++timers;
  EXPECT_EQ(timers, 2u) << out;  // element 0 and .timer off itself
  EXPECT_NE(out.find("error: unknown query 'frobnicate'"), std::string::npos) << out;
  EXPECT_NE(out.find("error: unknown output mode 'banana'"), std::string::npos) << out;
  EXPECT_NE(out.find("error: element 999999 does not exist"), std::string::npos) << out;
  EXPECT_NE(out.find("node,x,y,z,kind,anchors\n0,0,0,0,anchored,\n"), std::string::npos) << out;
  EXPECT_NE(out.find("units:    m"), std::string::npos) << out;
  EXPECT_EQ(out.find("element,x,y,z,level,edge,nodes\n1,"), std::string::npos) << "after .quit";
  EXPECT_EQ(snapshot(db), files) << "the shell wrote to the database";
}

// `--points -` in a script takes the lines after it, up to ".", and the
// script goes on after them: the same rows as a points file.
TEST(Shell, PointsFromTheLinesThatFollowAQuery) {
  testing::TempDir dir;
  const std::string db = testing::build_mesh(testing::small_sphere(), dir);
  const std::string points = "0 0 0\n3,4,5\nnot a point\n# a comment\n7 1 2\n";
  std::ofstream(dir.file("points.txt")) << points;
  const std::string same =
      testing::run("query " + db + " locate --points " + dir.file("points.txt") + " --format csv")
          .out;
  ASSERT_NE(same.find("bad"), std::string::npos) << same;
  ShellProcess sh(db, false);
  sh.send("locate --points - --format csv\n" + points + ".\nelement 0 --format csv\n" +
          "node-at --points - --format csv\n0 0 0\n");  // the input's end ends these points
  sh.close_input();
  const std::string out = sh.read_until("\x04");
  EXPECT_EQ(sh.wait(), 1) << out;  // a bad line
  const size_t rows = out.find(same);
  EXPECT_NE(rows, std::string::npos) << "the rows of the points file:\n" << out;
  EXPECT_NE(out.find("stdin:3: 'not' is not a whole number"), std::string::npos) << out;
  const size_t element = out.find("element,x,y,z,level,edge,nodes\n0,0,0,0,", rows);
  EXPECT_NE(element, std::string::npos) << "the script goes on after '.':\n" << out;
  EXPECT_NE(out.find("x,y,z,status,node,kind\n0,0,0,node,0,anchored\n", element), std::string::npos)
      << out;
}

TEST(Shell, ReloadSeesTheNewestCommit) {
  testing::TempDir dir;
  const std::string db = testing::build_mesh(testing::small_sphere(), dir);
  ShellProcess sh(db, false);
  sh.send("element 0\n");
  const std::string before = sh.read_until("nodes");
  EXPECT_NE(before.find("element 0: corner (0 0 0)"), std::string::npos) << before;
  // A new octree is imported while the shell holds its snapshot.
  GenOptions g;
  g.kind = GenOptions::Kind::kUniform;
  g.level = 1;
  std::vector<Octant> eight;
  ASSERT_OK(generate_octree(g, &eight));
  ASSERT_OK(write_octant_text(dir.file("u.txt"), eight, ""));
  ImportResult ir;
  ASSERT_OK(import_octants(db, dir.file("u.txt"), ImportOptions{}, &ir));
  sh.send("element 1\n.reload\nelement 1\n.quit\n");
  const std::string out = sh.read_until("level 1,");
  EXPECT_NE(out.find("reloaded: 8 elements, 0 nodes"), std::string::npos) << out;
  EXPECT_NE(out.find("element 1: corner (524288 0 0), level 1,"), std::string::npos) << out;
  EXPECT_EQ(sh.wait(), 0) << out;
}

TEST(Shell, LineEditingAndHistoryOnATerminal) {
  testing::TempDir dir;
  const std::string db = testing::build_mesh(testing::small_sphere(), dir);
  ShellProcess sh(db, true);
  sh.prompt_after("Enter \".help\"");
  // "elment 2", then Home, right twice, insert 'e': "element 2".
  sh.send("elment 2\x1b[H\x1b[C\x1b[Ce\r");
  sh.prompt_after("element 2: corner");
  // Up arrow recalls it; Backspace and '5' make it "element 5".
  sh.send(
      "\x1b[A\x7f"
      "5\r");
  sh.prompt_after("element 5: corner");
  // Ctrl-C while a long points file is answered ends that question only.
  {
    std::ofstream points(dir.file("many.txt"));
    for (int i = 0; i < 3000000; ++i) points << (i % 1000) * 1000 << " 5 5\n";
  }
  sh.send("locate --points " + dir.file("many.txt") + " --format csv\r");
  sh.read_until("inside");
  sh.send("\x03");
  sh.prompt_after("interrupted at line");
  // Ctrl-U drops a typed line; Ctrl-D on an empty line leaves.
  sh.send("garbage\x15.show\r");
  sh.prompt_after("timer:");
  sh.send("\x04");
  const std::string out = sh.read_until("\x04");
  EXPECT_EQ(sh.wait(), 0) << out;
  EXPECT_NE(out.find("Enter \".help\""), std::string::npos) << out;
  EXPECT_NE(out.find("element 2: corner"), std::string::npos) << out;
  EXPECT_NE(out.find("element 5: corner"), std::string::npos) << out;
  EXPECT_NE(out.find("error: interrupted at line"), std::string::npos) << out.substr(0, 2000);
  EXPECT_EQ(out.find("error", out.find("interrupted") + 1), std::string::npos);
  EXPECT_EQ(out.find("error"), out.find("error: interrupted"));
}

}  // namespace
}  // namespace weaver
