// DDS Security (Cyclone's built-in plug-ins, material from
// scripts/make-dds-certs.sh): with remote control on, the operator identity
// swaps a node; a tool without credentials does not even find the kernel; the
// read-only monitor identity may not publish commands.
#include <gtest/gtest.h>

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

namespace {

using namespace std::chrono_literals;

const std::string kPlr = PLR_BINARY;

int sh(const std::string& command, std::string* out = nullptr) {
  FILE* p = ::popen((command + " 2>&1").c_str(), "r");
  if (!p) return -1;
  char buf[4096];
  std::size_t n = 0;
  std::string sink;
  while ((n = std::fread(buf, 1, sizeof buf, p)) > 0) (out ? out : &sink)->append(buf, n);
  const int status = ::pclose(p);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

std::string slurp(const std::string& path) {
  std::ifstream f(path);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

// A process started as `argv` (in network namespace `ns` unless empty) with
// stdout and stderr to `log`. Joined here rather than by `ip netns exec`,
// which forks: the pid must be plr's own, to stop and kill it.
struct Proc {
  pid_t pid = -1;
  std::string log;
  Proc(const std::string& ns, const std::vector<std::string>& argv, std::string log_path)
      : log(std::move(log_path)) {
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

TEST(RemoteSecurity, SwapAcceptedWithPermissionRefusedWithout) {
  const auto dir = ::testing::TempDir() + "plr_dds_security/";
  std::string out;
  ASSERT_EQ(sh("rm -rf " + dir + " && " + std::string(PLR_SOURCE_DIR) +
                   "/scripts/make-dds-certs.sh " + dir + "certs kernel",
               &out),
            0)
      << out;
  const int domain = 100 + (::getpid() + 25) % 100;
  const auto config = dir + "secure.yaml";
  std::ofstream(config) << "pipeline: secure\nnodes:\n  doubler: {plugin: demo_doubler}\n"
                        << "remote:\n  dds: {domain: " << domain
                        << ", allow_remote_control: true, security_dir: " << dir
                        << "certs/kernel}\n";
  Proc kernel("", {kPlr, "run", config, "--report", dir + "report"}, dir + "kernel.log");
  const auto swap = [&](const std::string& identity, std::string* text) {
    text->clear();
    return sh(kPlr + " swap --remote secure doubler demo_doubler --domain " +
                  std::to_string(domain) +
                  (identity.empty() ? "" : " --security " + dir + "certs/" + identity),
              text);
  };
  std::string accepted;
  int rc = 1;
  for (int i = 0; i < 5 && rc != 0; ++i) rc = swap("operator", &accepted);
  EXPECT_EQ(rc, 0) << accepted << slurp(kernel.log);
  EXPECT_NE(accepted.find("now runs 'demo_doubler'"), std::string::npos) << accepted;

  std::string anonymous, monitor;
  EXPECT_EQ(swap("", &anonymous), 1);
  EXPECT_NE(anonymous.find("no kernel 'secure'"), std::string::npos) << anonymous;
  EXPECT_EQ(swap("monitor", &monitor), 1);
  EXPECT_NE(monitor.find("cannot create the control endpoints"), std::string::npos) << monitor;

  const auto log = slurp(kernel.log);
  EXPECT_NE(log.find("dds: remote command"), std::string::npos) << log;
  EXPECT_NE(log.find("node 'doubler' swapped to demo_doubler"), std::string::npos) << log;
}

}  // namespace
