// `plr`: the command line of the kernel.
#include "commands.hpp"
#include "monitor.hpp"

#include <CLI/CLI.hpp>

#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <string>

namespace {

// `plr NAME ARGS...` for a NAME plr does not know runs the program
// plr-NAME beside plr with ARGS, as git does: a plug-in's tools (`plr
// library` of the strategy generator) extend the command line while the
// kernel knows nothing of them. Returns only if there is no such program.
void run_external(int argc, char** argv, const CLI::App& app) {
  if (argc < 2 || argv[1][0] == '-' || std::strchr(argv[1], '/') != nullptr) return;
  for (const CLI::App* sub : app.get_subcommands({})) {
    if (sub->get_name() == argv[1]) return;
  }
  std::error_code ec;
  const auto self = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (ec) return;
  const std::string tool = (self.parent_path() / ("plr-" + std::string(argv[1]))).string();
  if (::access(tool.c_str(), X_OK) != 0) return;
  std::string name = "plr-" + std::string(argv[1]);
  argv[1] = name.data();
  ::execv(tool.c_str(), argv + 1);
  std::fprintf(stderr, "plr: %s: %s\n", tool.c_str(), std::strerror(errno));
  std::exit(1);
}

}  // namespace

int main(int argc, char** argv) {
  using namespace plr::kernel;
  CLI::App app{"PLR: plans, learns and reasons for a truck-unloading robot"};
  // List options (--set, --topics, ...) below take one value per use, so
  // `--set A=1 CONFIG` leaves CONFIG to the positional argument.
  app.require_subcommand(1);
  app.footer(
      "Other commands: `plr NAME ...` runs the program plr-NAME beside plr (e.g. plr library).");

  RunOptions run;
  auto* run_cmd = app.add_subcommand("run", "Run a pipeline until it finishes or Ctrl-C");
  run_cmd->add_option("config", run.config, "Pipeline config (YAML)")->required();
  run_cmd
      ->add_option("--set", run.overrides, "Override a config value: nodes.NODE.params.KEY=VALUE")
      ->type_name("KEY=VALUE")
      ->allow_extra_args(false);
  run_cmd->add_option("--duration", run.duration_s, "Stop after this many seconds (0: no limit)");
  run_cmd->add_option("--report", run.report_dir, "Folder for the run's report");
  run_cmd->add_option("--host", run.host, "Run only this host's nodes (used by the supervisor)");
  run_cmd->add_option("--run-id", run.run_id, "Shared-memory run id (used by the supervisor)");
  run_cmd->add_flag("-v,--verbose", run.verbose, "Debug logging");
  run_cmd->add_option("--record", run.record_file, "Record the run's topics to this MCAP file");
  run_cmd
      ->add_option("--record-max", run.record_max_bytes,
                   "--record: bytes of a part before the next starts (the last is FILE)")
      ->capture_default_str();
  run_cmd->add_option("--record-keep", run.record_keep, "--record: earlier parts kept")
      ->capture_default_str();
  run_cmd->add_option("--log", run.log_file,
                      "Write the run's output (its hosts' too) to this file, rotated");
  run_cmd
      ->add_option("--log-max", run.log_max_bytes,
                   "--log: bytes a file reaches before it becomes FILE.1")
      ->capture_default_str();
  run_cmd->add_option("--log-keep", run.log_keep, "--log: rotated files kept (FILE.1 ...)")
      ->capture_default_str();
  run_cmd->add_option("--record-topics", run.record_topics, "Topics to record ('*' wildcard)")
      ->delimiter(',')
      ->allow_extra_args(false);

  const auto dds_options = [](CLI::App* cmd, DdsToolOptions& o) {
    cmd->add_option("--domain", o.domain, "DDS domain")->capture_default_str();
    cmd->add_option("--interface", o.interfaces, "Network interfaces for DDS (default: lo)")
        ->allow_extra_args(false);
    cmd->add_option("--security", o.security_dir, "DDS Security material of this tool");
  };

  RunOptions record;
  RemoteRecordOptions remote_record_options;
  std::vector<std::string> record_args;
  auto* record_cmd = app.add_subcommand(
      "record",
      "Record chosen topics to an MCAP file: of a pipeline it runs (CONFIG FILE, = run "
      "--record), or of a running kernel over DDS (--remote KERNEL FILE)");
  record_cmd->add_option("args", record_args, "CONFIG FILE, or FILE with --remote")
      ->required()
      ->expected(1, 2);
  record_cmd->add_option("--topics", record.record_topics, "Topics ('*' wildcard; default all)")
      ->delimiter(',')
      ->allow_extra_args(false);
  record_cmd->add_option("--set", record.overrides, "Override a config value")
      ->allow_extra_args(false);
  record_cmd->add_option("--duration", record.duration_s, "Stop after this many seconds");
  record_cmd->add_option("--report", record.report_dir, "Folder for the run's report");
  record_cmd->add_option("--remote", remote_record_options.kernel,
                         "Record what this running kernel exports on DDS (id, pipeline@hostname, "
                         "pipeline name, or '*' for every kernel)");
  dds_options(record_cmd, remote_record_options.dds);

  RunOptions replay;
  auto* replay_cmd = app.add_subcommand(
      "replay", "Run a pipeline and publish an MCAP recording's messages on its bus");
  replay_cmd->add_option("file", replay.replay_file, "The recording (plr run --record)")
      ->required();
  replay_cmd->add_option("config", replay.config, "Pipeline config (YAML) to replay into")
      ->required();
  replay_cmd->add_option("--speed", replay.replay_speed, "Pace: 1 as recorded, 0 at once")
      ->capture_default_str();
  replay_cmd->add_option("--linger", replay.replay_linger_s, "Seconds to run on after the replay")
      ->capture_default_str();
  replay_cmd->add_option("--set", replay.overrides, "Override a config value")
      ->allow_extra_args(false);
  replay_cmd->add_option("--report", replay.report_dir, "Folder for the run's report");

  std::string validate_config;
  std::vector<std::string> validate_overrides;
  auto* validate_cmd =
      app.add_subcommand("validate", "Check a config (and its plug-ins) without running it");
  validate_cmd->add_option("config", validate_config, "Pipeline config (YAML)")->required();
  validate_cmd->add_option("--set", validate_overrides, "Override a config value")
      ->type_name("KEY=VALUE")
      ->allow_extra_args(false);
  bool validate_verbose = false;
  validate_cmd->add_flag("-v,--verbose", validate_verbose,
                         "Each shared-memory segment of the run, with its size");

  PluginsOptions plugins;
  auto* plugins_cmd = app.add_subcommand("plugins", "List the plug-ins found in the search paths");
  plugins_cmd->add_option("--config", plugins.config, "Use this config's plug-in paths");
  plugins_cmd->add_flag("--json", plugins.json, "One JSON array");

  SwapOptions swap;
  auto* swap_cmd =
      app.add_subcommand("swap", "Replace the plug-in behind a node of a running pipeline");
  swap_cmd->add_option("node", swap.node, "Node name")->required();
  swap_cmd->add_option("plugin", swap.plugin, "Plug-in to load in its place")->required();
  swap_cmd->add_option("--pipeline", swap.pipeline,
                       "Pipeline name (default: the only one running)");
  RemoteCommandOptions remote;
  const auto remote_options = [&](CLI::App* cmd) {
    cmd->add_option("--remote", remote.kernel,
                    "On this kernel over DDS (id, pipeline@hostname or pipeline name)");
    dds_options(cmd, remote.dds);
  };
  remote_options(swap_cmd);

  std::string node_name, node_pipeline;
  std::vector<CLI::App*> pause_resume_cmds;
  for (const char* what : {"pause", "resume"}) {
    auto* cmd = app.add_subcommand(
        what, std::string(what == std::string("pause") ? "Deactivate a node of a running pipeline"
                                                       : "Activate a paused node again"));
    cmd->add_option("node", node_name, "Node name")->required();
    cmd->add_option("--pipeline", node_pipeline, "Pipeline name (default: the only one running)");
    remote_options(cmd);
    pause_resume_cmds.push_back(cmd);
  }

  MonitorOptions monitor_options;
  auto* monitor_cmd =
      app.add_subcommand("monitor", "Kernels, nodes, topics and rates seen on a DDS domain");
  dds_options(monitor_cmd, monitor_options.dds);
  monitor_cmd->add_flag("--once", monitor_options.once, "Print once and exit");
  monitor_cmd->add_flag("--json", monitor_options.json, "JSON instead of a table");
  monitor_cmd
      ->add_option("--wait", monitor_options.wait_s, "--once: longest wait for kernels, seconds")
      ->capture_default_str();

  std::string status_pipeline;
  auto* status_cmd = app.add_subcommand("status", "Nodes and topics of a running pipeline (JSON)");
  status_cmd->add_option("--pipeline", status_pipeline,
                         "Pipeline name (default: the only one running)");

  app.add_subcommand("version", "Print the version and the plug-in ABI");

  run_external(argc, argv, app);
  CLI11_PARSE(app, argc, argv);

  if (*run_cmd) return run_pipeline(run);
  if (*record_cmd) {
    if (!remote_record_options.kernel.empty()) {
      if (record_args.size() != 1) {
        std::cerr << "plr: record --remote: give only the file to write\n";
        return 2;
      }
      remote_record_options.file = record_args[0];
      remote_record_options.topics = record.record_topics;
      remote_record_options.duration_s = record.duration_s;
      return remote_record(remote_record_options);
    }
    if (record_args.size() != 2) {
      std::cerr << "plr: record: give the pipeline config and the file to write (or --remote)\n";
      return 2;
    }
    record.config = record_args[0];
    record.record_file = record_args[1];
    return run_pipeline(record);
  }
  if (*replay_cmd) return run_pipeline(replay);
  if (*validate_cmd) return validate(validate_config, validate_overrides, validate_verbose);
  if (*plugins_cmd) return list_plugins(plugins);
  if (*swap_cmd && !remote.kernel.empty()) {
    remote.cmd = "swap";
    remote.node = swap.node;
    remote.plugin = swap.plugin;
    return remote_command(remote);
  }
  if (*swap_cmd) return swap_plugin(swap);
  for (auto* cmd : pause_resume_cmds) {
    if (!*cmd) continue;
    if (remote.kernel.empty()) return pause_resume(cmd->get_name(), node_name, node_pipeline);
    remote.cmd = cmd->get_name();
    remote.node = node_name;
    return remote_command(remote);
  }
  if (*monitor_cmd) return monitor(monitor_options);
  if (*status_cmd) return status(status_pipeline);
  return print_version();
}
