// The kernel of one process: loads the plug-ins of its nodes, runs their life
// cycle, owns the bus, swaps plug-ins while the pipeline runs, and publishes
// telemetry. It knows nothing about robots.
#pragma once

#include "bus.hpp"
#include "node_instance.hpp"
#include "pipeline_config.hpp"
#include "plugin_loader.hpp"

#include <plr/expected.hpp>

#include <flatbuffers/flatbuffers.h>

#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace plr::kernel {

struct NodeStatus {
  std::string name;
  std::string plugin;
  std::string version;
  std::string kind;
  std::string state;
  std::string host;
};

class Kernel {
 public:
  // `host` selects the nodes this process runs ("main" for the supervisor).
  // With a `run_id` and nodes on several hosts, the bus reaches the other
  // hosts' processes over shared memory.
  explicit Kernel(PipelineConfig config, std::string host = "main", std::string run_id = "");
  ~Kernel();  // stops everything still running
  Kernel(const Kernel&) = delete;
  Kernel& operator=(const Kernel&) = delete;

  // Loads, creates, configures and activates every node of this host. On an
  // error, whatever was started is stopped again and the error names the node.
  Status start();
  // Deactivates (reverse order), cleans up and unloads every node.
  void stop();

  // Replaces the plug-in behind a running node. The new one is loaded,
  // configured and activated beside the old; then the node's topics and
  // services move to it in one step; the old one answers what it already
  // accepted, and is then deactivated and unloaded. On failure the old one
  // keeps running and the error says why. Refused before anything changes:
  // a plug-in of another kind, one that would not offer every service the
  // node offers, and any swap of a node that holds the run's state
  // (executor, generator, simulator, driver), which plug-ins cannot hand over.

  Status swap(const std::string& node, const std::string& plugin);
  // Pauses a running node: it stops receiving topics and new calls and is
  // deactivated (the plug-in's deactivate hook). Resume activates it again.
  Status pause(const std::string& node);
  Status resume(const std::string& node);

  // Binds the pipeline clock to the simulator's `clock` topic (clock: sim).
  Status follow_sim_clock();
  // Calls `fn(ok, reason)` when a node announces on `pipeline/done` that the job is over.
  Status on_pipeline_done(std::function<void(bool, std::string)> fn);
  // Calls `fn(node, figures)` for each report a node publishes on `pipeline/report`.
  Status on_node_report(std::function<void(std::string, std::string)> fn);
  // Waits until these callbacks have handled every message this process's
  // nodes published so far (after stop(): what they sent while stopping).
  void drain_listeners();

  // Waits until the transports have set up what the started nodes
  // registered; an error names what other hosts cannot reach.
  Status sync_transports();

  Bus& bus() { return bus_; }
  const PipelineConfig& config() const { return config_; }
  const PipelineClock& clock() const { return clock_; }
  PluginLoader& loader() { return loader_; }
  std::vector<NodeStatus> nodes() const;
  // Telemetry as JSON (nodes, topics, services), for `plr monitor` and the control socket.
  std::string telemetry_json();
  // The same as a message (plr.msg.KernelTelemetry), for `kernel/telemetry`.
  void telemetry_message(flatbuffers::FlatBufferBuilder& fbb);

 private:
  struct Slot {
    NodeConfig config;
    std::unique_ptr<NodeInstance> instance;
    // Held through a whole swap, pause or resume: one change to a node at a time.
    std::mutex swap_mutex;
    // Held only while `config` or `instance` change, so status readers on the
    // control or DDS thread never wait for a swap draining in-flight calls.
    mutable std::mutex view_mutex;
  };
  class Internal;

  // Loaded, created and configured; bring_up() also activates it.
  Expected<std::unique_ptr<NodeInstance>> configured(const NodeConfig& config);
  Expected<std::unique_ptr<NodeInstance>> bring_up(const NodeConfig& config);
  template <class T>
  Status listen(const std::string& topic, std::function<void(const T&)> fn);
  Slot* slot(const std::string& name);

  PipelineConfig config_;
  std::string host_;
  std::string run_id_;
  PluginLoader loader_;
  PipelineClock clock_;
  Bus bus_;
  std::vector<std::unique_ptr<Slot>> slots_;
  std::unique_ptr<Internal> internal_;
  // Set and cleared on the thread that starts and destroys the kernel, under
  // `transports_mutex_`: telemetry_json() reads them from the control-socket
  // and DDS heartbeat threads, which run before start() sets them and until
  // the DDS bridge is destroyed.
  std::mutex transports_mutex_;
  std::unique_ptr<class ShmBridge> bridge_;
  std::unique_ptr<class DdsBridge> dds_;  // main host only, when remote.dds is configured
  // Kernel-side subscriptions (clock, pipeline/done, pipeline/report), alive as long as the kernel.
  std::vector<std::unique_ptr<std::function<void(const plr_msg*)>>> listeners_;
  std::unique_ptr<class TelemetryPublisher> telemetry_;
  bool started_ = false;
};

std::vector<std::string> plugin_search_paths(const PipelineConfig& config);

}  // namespace plr::kernel
