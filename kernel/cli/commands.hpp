// The subcommands of `plr`; each returns the process exit code.
#pragma once

#include "pipeline_config.hpp"

#include <plr/plugin_abi.h>
#include <plr/expected.hpp>

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
  // Recording: the main host writes these topics ('*' wildcard; none: all) to an MCAP file.
  std::string record_file;
  std::vector<std::string> record_topics;
  // In parts of at most this many bytes, `record_keep` earlier ones kept (recorder.hpp).
  std::uint64_t record_max_bytes = std::uint64_t{256} << 20;
  int record_keep = 3;
  // Replay: the main host publishes this MCAP file's messages on its bus
  // (speed 0: as fast as possible), then the run ends `replay_linger_s` later.
  std::string replay_file;
  double replay_speed = 1.0;
  double replay_linger_s = 2.0;
  // The run's stdout and stderr (its hosts' too) to this file, rotated
  // (log_file.hpp); empty: they stay where they are.
  std::string log_file;
  std::uint64_t log_max_bytes = std::uint64_t{16} << 20;
  int log_keep = 3;
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

// The exit code of every command for an error of this kind (docs/errors.md):
// 2 invalid input, 3 timeout, 4 unavailable, 5 cancelled, 6 wrong state,
// 1 internal; `plr run` adds 1 (the job failed) and 128 + signal.
int exit_code(plr_status code);
// Prints "plr: MESSAGE" to stderr (control bytes escaped, one problem a
// line) and returns `code`, or for an Error its kind's exit code.
int fail(const std::string& message, int code = 1);
int fail(const Error& error);

// The config with `overrides` ("KEY=VALUE") applied.
Expected<PipelineConfig> load_config(const std::string& file,
                                     const std::vector<std::string>& overrides);

// A Run (run.hpp) driven from a loop that takes SIGINT, SIGTERM and SIGHUP.
int run_pipeline(const RunOptions& options);
// Checks the config and its plug-ins and prints the run's /dev/shm need
// (each segment with `verbose`).
int validate(const std::string& config, const std::vector<std::string>& overrides,
             bool verbose = false);
int list_plugins(const PluginsOptions& options);
int swap_plugin(const SwapOptions& options);
// `cmd` is "pause" or "resume".
int pause_resume(const std::string& cmd, const std::string& node, const std::string& pipeline);
int status(const std::string& pipeline);
int print_version();

}  // namespace plr::kernel
