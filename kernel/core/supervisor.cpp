#include "supervisor.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <fcntl.h>
#include <poll.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>
#include <algorithm>
#include <cerrno>
#include <csignal>
#include <cstring>
#include <thread>

namespace plr::kernel {

std::vector<std::string> hosts_with_nodes(const PipelineConfig& config) {
  std::vector<std::string> out;
  for (const auto& n : config.nodes)
    if (std::find(out.begin(), out.end(), n.host) == out.end()) out.push_back(n.host);
  return out;
}

Supervisor::Supervisor(std::vector<std::string> command, std::vector<HostConfig> hosts,
                       std::string run_id)
    : command_(std::move(command)), run_id_(std::move(run_id)) {
  for (auto& h : hosts) {
    Host host;
    host.config = std::move(h);
    hosts_.push_back(std::move(host));
  }
}

Supervisor::~Supervisor() {
  stop();
}

Status Supervisor::spawn(Host& host) {
  int ready[2];
  if (::pipe2(ready, O_CLOEXEC) != 0)
    return make_error(PLR_ERR_INTERNAL,
                      fmt::format("host '{}': pipe: {}", host.config.name, std::strerror(errno)));
  std::vector<std::string> args = command_;
  for (const auto& a : {std::string("--host"), host.config.name, std::string("--run-id"), run_id_})
    args.push_back(a);
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid < 0)
    return make_error(PLR_ERR_INTERNAL,
                      fmt::format("host '{}': fork: {}", host.config.name, std::strerror(errno)));
  if (pid == 0) {
    ::setpgid(0, 0);
    ::prctl(PR_SET_PDEATHSIG, SIGTERM);
    if (::getppid() != parent) ::_exit(1);  // the supervisor died before prctl
    ::fcntl(ready[1], F_SETFD, 0);          // this one end survives exec
    ::setenv("PLR_READY_FD", std::to_string(ready[1]).c_str(), 1);
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  ::close(ready[1]);
  host.pid = pid;
  host.ready_fd = ready[0];
  spdlog::info("host '{}' started (pid {})", host.config.name, pid);
  return {};
}

Status Supervisor::start(std::chrono::milliseconds ready_timeout) {
  for (auto& h : hosts_)
    if (auto s = spawn(h); !s) return s;
  const auto deadline = std::chrono::steady_clock::now() + ready_timeout;
  for (auto& h : hosts_) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    pollfd p{h.ready_fd, POLLIN, 0};
    char c = 0;
    const bool ok = ::poll(&p, 1, static_cast<int>(std::max<std::int64_t>(left.count(), 0))) == 1 &&
                    ::read(h.ready_fd, &c, 1) == 1;
    ::close(h.ready_fd);
    h.ready_fd = -1;
    if (!ok)
      return make_error(
          PLR_ERR_UNAVAILABLE,
          fmt::format("host '{}' did not start its nodes (see its log above)", h.config.name));
  }
  return {};
}

Status Supervisor::poll() {
  const auto now = std::chrono::steady_clock::now();
  for (auto& h : hosts_) {
    if (h.waiting_restart && now >= h.restart_at) {
      h.waiting_restart = false;
      if (auto s = spawn(h); !s) return s;
      if (h.ready_fd >= 0) {
        ::close(h.ready_fd);
        h.ready_fd = -1;
      }
      continue;
    }
    if (h.pid <= 0) continue;
    int status = 0;
    const pid_t r = ::waitpid(h.pid, &status, WNOHANG);
    if (r != h.pid) continue;
    h.pid = -1;
    const bool clean = WIFEXITED(status) && WEXITSTATUS(status) == 0;
    const std::string how = WIFSIGNALED(status)
                                ? fmt::format("killed by signal {}", WTERMSIG(status))
                                : fmt::format("exited with code {}", WEXITSTATUS(status));
    if (clean) {
      spdlog::info("host '{}' finished", h.config.name);
      continue;
    }
    const auto window = std::chrono::duration_cast<std::chrono::steady_clock::duration>(
        std::chrono::duration<double>(h.config.restart_window_s));
    while (!h.crashes.empty() && now - h.crashes.front() > window) h.crashes.pop_front();
    h.crashes.push_back(now);
    const int in_window = static_cast<int>(h.crashes.size());
    if (h.config.restart == RestartPolicy::Never)
      return make_error(
          PLR_ERR_UNAVAILABLE,
          fmt::format("host '{}' {} and is not restarted (policy never)", h.config.name, how));
    if (in_window > h.config.max_restarts)
      return make_error(
          PLR_ERR_UNAVAILABLE,
          fmt::format("host '{}' {} and is not restarted: {} crashes within {} s (max_restarts "
                      "{}, restart_window_s {}; {} restarts in the run)",
                      h.config.name, how, in_window, h.config.restart_window_s,
                      h.config.max_restarts, h.config.restart_window_s, h.restarts));
    const auto backoff =
        std::chrono::milliseconds(h.config.backoff_ms) * (1 << std::min(in_window - 1, 10));
    ++h.restarts;
    h.waiting_restart = true;
    h.restart_at = now + backoff;
    spdlog::warn("host '{}' {}; restarting in {} ms ({} of at most {} crashes within {} s)",
                 h.config.name, how, backoff.count(), in_window, h.config.max_restarts,
                 h.config.restart_window_s);
  }
  return {};
}

void Supervisor::stop() {
  for (auto& h : hosts_) {
    h.waiting_restart = false;
    if (h.pid > 0) ::kill(h.pid, SIGTERM);
  }
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  for (auto& h : hosts_) {
    while (h.pid > 0) {
      int status = 0;
      if (::waitpid(h.pid, &status, WNOHANG) == h.pid) {
        h.pid = -1;
        break;
      }
      if (std::chrono::steady_clock::now() > deadline) {
        spdlog::warn("host '{}' did not stop; killing it", h.config.name);
        ::kill(h.pid, SIGKILL);
        ::waitpid(h.pid, &status, 0);
        h.pid = -1;
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    if (h.ready_fd >= 0) {
      ::close(h.ready_fd);
      h.ready_fd = -1;
    }
  }
}

int Supervisor::restarts() const {
  int n = 0;
  for (const auto& h : hosts_) n += h.restarts;
  return n;
}

}  // namespace plr::kernel
