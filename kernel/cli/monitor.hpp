// Remote tools over Cyclone DDS: `plr monitor` (read-only: kernels, nodes,
// topics, rates from every kernel's telemetry) and `plr swap|pause|resume
// --remote` (commands the target kernel refuses unless remote control is on).
#pragma once

#include <string>
#include <vector>

namespace plr::kernel {

struct DdsToolOptions {
  int domain = 0;
  std::vector<std::string> interfaces{"lo"};
  std::string security_dir;  // this tool's identity, when the domain uses DDS Security
};

struct MonitorOptions {
  DdsToolOptions dds;
  bool once = false;
  bool json = false;
  double wait_s = 3.0;  // --once: longest wait for kernels to show up
};

// A command for one node of a remote kernel: "swap" (to `plugin`), "pause" or "resume".
struct RemoteCommandOptions {
  DdsToolOptions dds;
  std::string kernel;  // full id, "pipeline@hostname" or the pipeline name
  std::string cmd;
  std::string node;
  std::string plugin;
};

int monitor(const MonitorOptions& options);
int remote_command(const RemoteCommandOptions& options);

}  // namespace plr::kernel
