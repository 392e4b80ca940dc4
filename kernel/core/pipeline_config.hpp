// The pipeline config (YAML): what nodes run, with which plug-ins and
// parameters, in which host processes, and what crosses machines.
#pragma once

#include <plr/expected.hpp>
#include <plr/yaml_reader.hpp>

#include <nlohmann/json.hpp>

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace plr::kernel {

enum class RestartPolicy { Never, OnFailure };

struct HostConfig {
  std::string name;
  RestartPolicy restart = RestartPolicy::OnFailure;
  // Given up once a host crashed more than max_restarts times within the
  // last restart_window_s seconds (as supervisors do): rare crashes spread
  // over a long run are each restarted.
  int max_restarts = 5;
  double restart_window_s = 60;
  int backoff_ms = 200;  // doubles with each crash in the window
  yaml::Location where;  // of its key, for error messages
};

enum class TopicPolicy { KeepLast, Reliable };

struct TopicSettings {
  std::string name;
  TopicPolicy policy = TopicPolicy::KeepLast;
  std::size_t depth = 64;  // queued messages per subscriber
  // Bytes per message, for shared memory and DDS; unset: the bound of the
  // topic's (or service's) message types (slot_size.hpp).
  std::optional<std::size_t> slot_size;
  bool busy_poll = false;     // shared-memory readers spin instead of sleeping
  std::uint32_t spin_us = 0;  // shared-memory readers spin this long, then sleep
  yaml::Location where;       // of its key, for error messages
};

struct NodeConfig {
  std::string name;
  std::string plugin;
  std::string host = "main";
  nlohmann::json params = nlohmann::json::object();
  std::map<std::string, std::string> remap;  // name used by the plug-in -> bus name
  yaml::Location where;                      // of its key, for error messages
};

struct DdsConfig {
  bool enabled = false;
  int domain = 0;
  std::vector<std::string> interfaces{"lo"};
  std::vector<std::string> export_patterns;  // topic or service names, '*' wildcards
  std::vector<std::string> import_patterns;
  // Idempotent services whose calls are re-sent when their provider is lost
  // (once to each other live provider); the others' calls fail.
  std::vector<std::string> resend_patterns;
  bool allow_remote_control = false;
  std::string security_dir;  // DDS Security material; required for remote control
};

struct PipelineConfig {
  std::string file;      // absolute path of the YAML file
  std::string pipeline;  // name of the run; defaults to the file's stem
  std::vector<std::string>
      plugin_paths;            // absolute; relative entries resolve against the file's folder
  std::string clock = "wall";  // "wall" or "sim" (time from the `clock` topic)
  // While the run lasts, idle CPUs must wake within this many µs (Linux PM
  // QoS): 0 makes cross-core futex wake-ups several times cheaper on machines
  // with a slow idle exit, at the cost of power. Unset: the machine's setting.
  std::optional<std::int32_t> cpu_wake_latency_us;
  std::vector<NodeConfig> nodes;
  std::vector<HostConfig> hosts;  // always contains "main"
  std::vector<TopicSettings> topics;
  DdsConfig dds;

  const NodeConfig* node(const std::string& name) const;
  const HostConfig* host(const std::string& name) const;
  // Settings for a topic: its own entry, or the defaults.
  TopicSettings topic(const std::string& name) const;
};

// One override from the command line: "nodes.sim.params.seed=3" (dotted path
// into the YAML; the value is parsed as YAML, so numbers stay numbers).
struct Override {
  std::string path;
  std::string value;
};

// Parses and validates; nothing starts before this succeeds. Every error is
// one line naming file:line:column and the key, e.g.
//   "configs/x.yaml:12:5: nodes.planner.plugin: expected a string"
Expected<PipelineConfig> load_pipeline_config(const std::string& file,
                                              const std::vector<Override>& overrides = {});
Expected<PipelineConfig> parse_pipeline_config(const std::string& yaml_text,
                                               const std::string& file_name,
                                               const std::vector<Override>& overrides = {});
Expected<Override> parse_override(const std::string& text);  // "a.b.c=value"

// A name that becomes part of a file or segment name (pipeline, run id):
// letters, digits, '_', '-' and '.', not starting with '.', at most 64
// characters, so it can never name another folder ("../x") or file.
Status check_name(const std::string& name, const std::string& what);

// `text` with every byte that is not printable ASCII shown as \xNN, for
// messages that quote input.
std::string printable(std::string_view text);

}  // namespace plr::kernel
