// Runs a program as its child and writes the child's peak resident set, in
// bytes, to a file:
//
//   peak_rss_runner OUT PROGRAM [ARG...]
//
// It exits with the program's exit code, or 128 + the signal that ended it.
//
// Why: a test forks to run a program, and the kernel's peak for the child
// (wait4's ru_maxrss) keeps what the forked copy of the test held before
// its exec.  Run from a test process that has grown (other tests before it
// in the same process), a program's peak reads as the test's.  This small
// process in between forks the program from its own few hundred kilobytes,
// so the peak it writes is the program's.
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: peak_rss_runner OUT PROGRAM [ARG...]\n");
    return 2;
  }
  const pid_t pid = fork();
  if (pid < 0) return 2;
  if (pid == 0) {
    execv(argv[2], argv + 2);
    _exit(127);
  }
  int status = 0;
  struct rusage usage {};
  if (wait4(pid, &status, 0, &usage) != pid) return 2;
  std::FILE* out = std::fopen(argv[1], "w");
  if (out == nullptr) return 2;
  std::fprintf(out, "%ld\n", usage.ru_maxrss * 1024L);
  if (std::fclose(out) != 0) return 2;
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}
