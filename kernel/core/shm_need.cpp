#include "shm_need.hpp"

#include "segment_config.hpp"
#include "supervisor.hpp"
#include "telemetry_publisher.hpp"

#include <plr/message.hpp>
#include <plr/messages.hpp>
#include <plr/shm/service.hpp>
#include <plr/shm/topic.hpp>

#include <fmt/format.h>

#include <sys/statvfs.h>
#include <algorithm>
#include <cerrno>
#include <cstring>
#include <memory>

namespace plr::kernel {

namespace {

// A declaration is the plug-in's memory: read defensively.
constexpr std::size_t kMaxPorts = 4096;

std::uint64_t type_of(const char* name) {
  return name != nullptr ? fnv1a(name) : 0;
}

std::string resolve(const NodeConfig& node, const char* name) {
  const auto it = node.remap.find(name);
  return it == node.remap.end() ? std::string(name) : it->second;
}

class Counter {
 public:
  Counter(const PipelineConfig& config, std::size_t hosts) : config_(config), hosts_(hosts) {}

  void topic(const std::string& host, const std::string& name, std::uint64_t type) {
    if (seen(host, name, false)) return;
    const auto c = topic_segment_config(config_.topic(name), type);
    add({host, name, false, c.slot_size, c.slot_count, shm::segment_bytes(c)});
  }

  void service(const std::string& host, const std::string& name, std::uint64_t request,
               std::uint64_t reply) {
    if (seen(host, name, true)) return;
    const auto c = service_segment_config(config_.topic(name), request, reply, hosts_);
    // A request ring and a reply ring per client channel.
    add({host, name, true, c.slot_size, std::size_t{2} * c.max_clients * c.slot_count,
         shm::segment_bytes(c)});
  }

  ShmNeed need;

 private:
  bool seen(const std::string& host, const std::string& name, bool service) const {
    return std::any_of(need.segments.begin(), need.segments.end(), [&](const SegmentNeed& s) {
      return s.host == host && s.name == name && s.service == service;
    });
  }
  void add(SegmentNeed s) {
    need.total += s.bytes;
    need.segments.push_back(std::move(s));
  }

  const PipelineConfig& config_;
  std::size_t hosts_;
};

}  // namespace

ShmNeed shm_need(const PipelineConfig& config,
                 const std::map<std::string, const plr_interface*>& interfaces) {
  const auto hosts = hosts_with_nodes(config);
  Counter count(config, hosts.size());
  if (hosts.size() < 2) return count.need;  // one process: the bus alone
  for (const auto& host : hosts) {
    count.topic(host, TelemetryPublisher::kTopic, MessageTraits<msg::KernelTelemetry>::type_id());
    for (const auto& node : config.nodes) {
      if (node.host != host) continue;
      const auto it = interfaces.find(node.name);
      const plr_interface* declared = it == interfaces.end() ? nullptr : it->second;
      if (declared == nullptr || declared->ports == nullptr || declared->port_count > kMaxPorts) {
        count.need.undeclared.push_back(node.name);
        continue;
      }
      for (std::size_t i = 0; i < declared->port_count; ++i) {
        const plr_port& p = declared->ports[i];
        if (p.name == nullptr) continue;
        if (p.kind == PLR_PORT_TOPIC) count.topic(host, resolve(node, p.name), type_of(p.type));
        if (p.kind == PLR_PORT_SERVICE)
          count.service(host, resolve(node, p.name), type_of(p.type), type_of(p.reply_type));
      }
    }
  }
  return count.need;
}

Expected<ShmNeed> shm_need(const PipelineConfig& config, PluginLoader& loader) {
  std::vector<std::shared_ptr<PluginLibrary>> keep;  // declarations live in the libraries
  std::map<std::string, const plr_interface*> interfaces;
  for (const auto& n : config.nodes) {
    auto lib = loader.load(n.plugin);
    if (!lib)
      return make_error(lib.error().code, fmt::format("{}: nodes.{}.plugin: {}", n.where.str(),
                                                      n.name, lib.error().message));
    interfaces[n.name] = (*lib)->declared_interface();
    keep.push_back(std::move(*lib));
  }
  return shm_need(config, interfaces);
}

Expected<std::size_t> free_bytes(const std::string& path) {
  struct statvfs s {};
  if (::statvfs(path.c_str(), &s) != 0)
    return make_error(PLR_ERR_UNAVAILABLE, fmt::format("{}: {}", path, std::strerror(errno)));
  return static_cast<std::size_t>(s.f_bavail) * static_cast<std::size_t>(s.f_frsize);
}

std::string format_bytes(std::size_t bytes) {
  constexpr const char* kUnits[] = {"B", "KiB", "MiB", "GiB", "TiB"};
  double value = static_cast<double>(bytes);
  std::size_t unit = 0;
  while (value >= 1024 && unit + 1 < std::size(kUnits)) {
    value /= 1024;
    ++unit;
  }
  return unit == 0 ? fmt::format("{} B", bytes)
                   : fmt::format("{:.{}f} {}", value, value < 10 ? 2 : 1, kUnits[unit]);
}

}  // namespace plr::kernel
