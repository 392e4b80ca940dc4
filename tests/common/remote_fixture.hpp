// What the remote tests and benchmarks share: running shell commands and
// `plr` processes (optionally inside a network namespace), reading their
// logs, and a network namespace joined to this one.
#pragma once

#include <fcntl.h>
#include <sched.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace plr::remote_test {

using namespace std::chrono_literals;

#ifdef PLR_BINARY
inline const std::string kPlr = PLR_BINARY;
#endif

// Runs `command` with sh; its exit code, stdout and stderr into `out`.
inline int sh(const std::string& command, std::string* out = nullptr) {
  FILE* p = ::popen((command + " 2>&1").c_str(), "r");
  if (!p) return -1;
  char buf[4096];
  std::size_t n = 0;
  std::string sink;
  while ((n = std::fread(buf, 1, sizeof buf, p)) > 0) (out ? out : &sink)->append(buf, n);
  const int status = ::pclose(p);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

inline std::string slurp(const std::string& path) {
  std::ifstream f(path);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

inline std::string write_file(const std::string& path, const std::string& text) {
  std::ofstream(path) << text;
  return path;
}

// A process started as `argv` (in network namespace `ns` unless empty) with
// stdout and stderr to `log`. Joined here rather than by `ip netns exec`,
// which forks: the pid must be plr's own, to stop and kill it.
struct Proc {
  pid_t pid = -1;
  std::string log;
  Proc(const std::string& ns, const std::vector<std::string>& argv, std::string log_path)
      : log(std::move(log_path)) {
    // Emptied before the fork: a reader must never see an earlier run's log.
    if (const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644); fd >= 0)
      ::close(fd);
    pid = ::fork();
    if (pid == 0) {
      if (!ns.empty()) {
        const int nsfd = ::open(("/run/netns/" + ns).c_str(), O_RDONLY | O_CLOEXEC);
        if (nsfd < 0 || ::setns(nsfd, CLONE_NEWNET) != 0) ::_exit(126);
      }
      const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      ::dup2(fd, 1);
      ::dup2(fd, 2);
      std::vector<char*> args;
      for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
      args.push_back(nullptr);
      ::execvp(args[0], args.data());
      ::_exit(127);
    }
  }
  Proc(const Proc&) = delete;
  Proc& operator=(const Proc&) = delete;
  // Exit code, or -1 when it did not end within `timeout`.
  int wait(std::chrono::milliseconds timeout) {
    const auto end = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < end) {
      int status = 0;
      if (::waitpid(pid, &status, WNOHANG) == pid) {
        pid = -1;
        return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      }
      std::this_thread::sleep_for(20ms);
    }
    return -1;
  }
  // A clean stop first, so the kernel removes its control socket.
  ~Proc() {
    if (pid <= 0) return;
    ::kill(pid, SIGTERM);
    ::kill(pid, SIGCONT);
    if (wait(5s) == -1) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, nullptr, 0);
    }
  }
};

// Polls `done` every 50 ms until it holds or `timeout` passes; whether it held.
template <class Fn>
bool eventually(std::chrono::milliseconds timeout, Fn&& done) {
  const auto end = std::chrono::steady_clock::now() + timeout;
  while (!done()) {
    if (std::chrono::steady_clock::now() > end) return false;
    std::this_thread::sleep_for(50ms);
  }
  return true;
}

// A network namespace with a veth pair to this one ("another machine"):
// 10.78.N.1 there, 10.78.N.254 here, N from the pid. Removed again at the
// end. Where namespaces are not permitted, `isolated` is false, `why_not`
// says why, and both sides are on loopback.
struct VethNamespace {
  bool isolated = false;
  std::string why_not, ns, veth;
  std::string here = "lo", there = "lo";  // each side's interface

  VethNamespace() {
    const auto tag = std::to_string(::getpid() % 100000);
    const auto subnet = "10.78." + std::to_string(::getpid() % 250);
    ns = "plrw" + tag;
    veth = "w" + tag;
    const std::vector<std::string> steps = {
        "ip netns add " + ns,
        "ip link add " + veth + " type veth peer name plr0 netns " + ns,
        "ip addr add " + subnet + ".254/24 dev " + veth,
        "ip link set " + veth + " up",
        "ip -n " + ns + " addr add " + subnet + ".1/24 dev plr0",
        "ip -n " + ns + " link set plr0 up",
        "ip -n " + ns + " link set lo up",
    };
    for (const auto& s : steps) {
      std::string out;
      if (sh(s, &out) != 0) {
        why_not = s + ": " + out;
        return;
      }
    }
    isolated = true;
    here = veth;
    there = "plr0";
  }
  VethNamespace(const VethNamespace&) = delete;
  VethNamespace& operator=(const VethNamespace&) = delete;
  ~VethNamespace() {
    sh("ip netns del " + ns + " 2>/dev/null");
    sh("ip link del " + veth + " 2>/dev/null");
  }
  // The namespace to start a process in ("": this one).
  std::string target() const { return isolated ? ns : ""; }
};

}  // namespace plr::remote_test
