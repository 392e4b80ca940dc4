// The /dev/shm a run of a pipeline takes. A run that spans hosts makes, on
// each host, one segment per topic its nodes advertise (its kernel's
// telemetry too) and one per service they provide (docs/transports.md); a
// run on one host makes none. Counted from what the plug-ins declare
// (plr/interface.hpp), before anything starts.
#pragma once

#include "pipeline_config.hpp"
#include "plugin_loader.hpp"

#include <plr/plugin_abi.h>
#include <plr/expected.hpp>

#include <cstddef>
#include <map>
#include <string>
#include <vector>

namespace plr::kernel {

struct SegmentNeed {
  std::string host;
  std::string name;  // of the topic or service
  bool service = false;
  std::size_t slot_size = 0;  // bytes per message
  std::size_t slots = 0;      // in the whole segment
  std::size_t bytes = 0;      // of /dev/shm (whole pages)
};

struct ShmNeed {
  std::vector<SegmentNeed> segments;
  std::size_t total = 0;
  // Nodes whose plug-in declares nothing: their segments are not counted.
  std::vector<std::string> undeclared;
};

// `interfaces`: each node's declaration by node name (nullptr: none).
ShmNeed shm_need(const PipelineConfig& config,
                 const std::map<std::string, const plr_interface*>& interfaces);

// Loads each node's plug-in to read its declaration. Errors are the
// loader's, naming the node: "nodes.sim.plugin: ...".
Expected<ShmNeed> shm_need(const PipelineConfig& config, PluginLoader& loader);

// Bytes an unprivileged process may still allocate on the file system that
// holds `path` (statvfs), or why not known.
Expected<std::size_t> free_bytes(const std::string& path);

// 1288 MiB as "1.26 GiB", 96 KiB as "96.0 KiB": for people; exact counts go beside it.
std::string format_bytes(std::size_t bytes);

}  // namespace plr::kernel
