// The subcommands of `plr`; each returns the process exit code.
#pragma once

#include <string>
#include <vector>

namespace plr::kernel {

struct RunOptions {
  std::string config;
  std::vector<std::string> overrides;
  double duration_s = 0;
  std::string report_dir;
  std::string host = "main";
  std::string run_id;
  bool verbose = false;
};

struct PluginsOptions {
  std::string config;
  bool json = false;
};

struct SwapOptions {
  std::string node;
  std::string plugin;
  std::string pipeline;
};

int run_pipeline(const RunOptions& options);
int validate(const std::string& config, const std::vector<std::string>& overrides);
int list_plugins(const PluginsOptions& options);
int swap_plugin(const SwapOptions& options);
// `cmd` is "pause" or "resume".
int pause_resume(const std::string& cmd, const std::string& node, const std::string& pipeline);
int status(const std::string& pipeline);
int print_version();

}  // namespace plr::kernel
