// Starts the non-main hosts of a pipeline as child processes of the same
// `plr` binary, watches them, and restarts a crashed one per its policy.
// Children live in their own process group (Ctrl-C reaches only us; we stop
// them in order) and die with us (PR_SET_PDEATHSIG).
#pragma once

#include "pipeline_config.hpp"

#include <plr/expected.hpp>

#include <sys/types.h>

#include <chrono>
#include <deque>
#include <string>
#include <vector>

namespace plr::kernel {

class Supervisor {
 public:
  // `command`: the plr binary and the arguments every host gets (run CONFIG
  // --set ...); `--host NAME --run-id ID` are added per host.
  Supervisor(std::vector<std::string> command, std::vector<HostConfig> hosts, std::string run_id);
  ~Supervisor();  // stops the hosts
  Supervisor(const Supervisor&) = delete;
  Supervisor& operator=(const Supervisor&) = delete;

  // Starts every host and waits until each reports its nodes active.
  Status start(std::chrono::milliseconds ready_timeout);
  // Reaps hosts that exited and restarts them per policy. An error once a
  // host is down for good (policy `never`, or more than max_restarts crashes
  // within restart_window_s).
  Status poll();
  // Asks every host to stop (SIGTERM), then kills what is left after a grace period.
  void stop();
  int restarts() const;

 private:
  struct Host {
    HostConfig config;
    pid_t pid = -1;
    int ready_fd = -1;
    int restarts = 0;                                           // over the whole run
    std::deque<std::chrono::steady_clock::time_point> crashes;  // within the window
    std::chrono::steady_clock::time_point restart_at{};
    bool waiting_restart = false;
  };
  Status spawn(Host& host);

  std::vector<std::string> command_;
  std::vector<Host> hosts_;
  std::string run_id_;
};

// The hosts that have at least one node, "main" included when it has any.
std::vector<std::string> hosts_with_nodes(const PipelineConfig& config);

}  // namespace plr::kernel
