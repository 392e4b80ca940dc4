// Remote tools over Cyclone DDS: `plr monitor` (read-only: kernels, nodes,
// topics, rates from every kernel's telemetry), `plr record --remote`
// (read-only: the topics a running kernel exports, into an MCAP file) and
// `plr swap|pause|resume --remote` (commands the target kernel refuses
// unless remote control is on).
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

// Records the topics kernels export on DDS (remote.dds.export) into an MCAP
// file, as `plr run --record` does on the bus, until Ctrl-C or `duration_s`.
struct RemoteRecordOptions {
  DdsToolOptions dds;
  std::string kernel;  // as RemoteCommandOptions::kernel; "*": every kernel
  std::string file;
  std::vector<std::string> topics;  // bus topic names, '*' wildcard; empty: all
  double duration_s = 0.0;          // 0: until interrupted
};

int monitor(const MonitorOptions& options);
int remote_record(const RemoteRecordOptions& options);
int remote_command(const RemoteCommandOptions& options);

}  // namespace plr::kernel
