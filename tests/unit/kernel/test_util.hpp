// Helpers for the tests of the shared-memory transport and of what uses it:
// unique run ids, the segments of a run, forked children, pipes.
#pragma once

#include <dirent.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "plr/shm/shm.hpp"

namespace plr::shm::test {

// Unique per test process and call, so tests may run in parallel.
inline std::string unique_run_id() {
  static std::atomic<int> n{0};
  return "t" + std::to_string(::getpid()) + "_" + std::to_string(n++);
}

// Names (in /dev/shm) of this user's segments of a run.
inline std::vector<std::string> run_segments(const std::string& run_id) {
  std::vector<std::string> out;
  const std::string prefix = "plr." + std::to_string(::geteuid()) + "." + run_id + ".";
  if (DIR* d = ::opendir("/dev/shm")) {
    while (dirent* e = ::readdir(d)) {
      if (std::strncmp(e->d_name, prefix.c_str(), prefix.size()) == 0) out.push_back(e->d_name);
    }
    ::closedir(d);
  }
  return out;
}

inline mode_t segment_mode(const std::string& shm_name) {
  struct stat st {};
  if (::stat(("/dev/shm" + shm_name).c_str(), &st) != 0) return 0;
  return st.st_mode & 0777;
}

// A one-way byte channel between parent and child, for "ready" handshakes.
struct Pipe {
  int fd[2] = {-1, -1};
  Pipe() {
    if (::pipe(fd) != 0) fd[0] = fd[1] = -1;
  }
  ~Pipe() {
    for (int f : fd) {
      if (f >= 0) ::close(f);
    }
  }
  void signal(char c = 'x') const { (void)!::write(fd[1], &c, 1); }
  // For a pipe only children write to: once the parent has closed its own
  // write end, wait() sees end-of-file when every child has exited, instead
  // of blocking for ever on a child that died without signalling.
  void close_write() {
    if (fd[1] >= 0) ::close(fd[1]);
    fd[1] = -1;
  }
  // Returns the byte, or 0 if the writer closed the pipe.
  char wait() const {
    char c = 0;
    return ::read(fd[0], &c, 1) == 1 ? c : 0;
  }
};

// Runs fn in a forked child that exits with fn's return value. The child is
// killed by an alarm if it hangs, so a deadlock fails the test, not the run.
template <class Fn>
pid_t fork_child(Fn fn, unsigned alarm_seconds = 60) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::alarm(alarm_seconds);
    ::_exit(fn());
  }
  return pid;
}

// Starts `argv` (argv[0]: the program's path) in a child process, its
// stdout and stderr written to `log` (a fresh file; /dev/null when empty).
inline pid_t spawn(const std::vector<std::string>& argv, const std::string& log) {
  const std::string out = log.empty() ? "/dev/null" : log;
  const pid_t pid = ::fork();
  if (pid == 0) {
    // Both appending: neither overwrites what the other wrote.
    if (std::FILE* f = std::fopen(out.c_str(), "w")) std::fclose(f);
    std::freopen(out.c_str(), "a", stdout);
    std::freopen(out.c_str(), "a", stderr);
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    ::execv(args[0], args.data());
    ::_exit(127);
  }
  return pid;
}

// Exit status of a child (or 128 + signal).
inline int wait_child(pid_t pid) {
  int status = 0;
  if (::waitpid(pid, &status, 0) != pid) return -1;
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
  return -1;
}

inline std::byte b(int v) {
  return static_cast<std::byte>(v);
}

}  // namespace plr::shm::test
