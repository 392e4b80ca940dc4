// Carries the bus between the host processes of one pipeline run over shared
// memory (kernel/transport/shm). Each process runs one bridge. What a local
// node publishes goes to a segment "<host>/<topic>" that other hosts read in
// place; what a local node subscribes to is read from every other host's
// segment of that topic; services a local node provides are served from
// "<host>/<service>"; calls nobody here provides go to a host that does: of
// several, the one with the fewest of our calls waiting on it.
// Plug-ins see none of this: where a node runs is config.
#pragma once

#include "bus.hpp"
#include "node_thread.hpp"
#include "pipeline_config.hpp"

#include <nlohmann/json.hpp>

#include <atomic>
#include <chrono>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace plr::kernel {

class ShmBridge final : public Endpoint, public Link {
 public:
  // `hosts`: every host of the run that has nodes, this one included.
  ShmBridge(Bus& bus, const PipelineConfig& config, std::string host,
            std::vector<std::string> hosts, std::string run_id);
  ~ShmBridge() override;
  ShmBridge(const ShmBridge&) = delete;
  ShmBridge& operator=(const ShmBridge&) = delete;

  NodeThread& node_thread() override { return node_thread_; }
  const std::string& endpoint_name() const override { return name_; }

  Endpoint& link_endpoint() override { return *this; }
  void topic_advertised(const std::string& topic, std::uint64_t type_id,
                        std::uint32_t schema_version) override;
  void topic_subscribed(const std::string& topic, std::uint64_t type_id) override;
  void service_provided(const std::string& service, std::uint64_t request_type,
                        std::uint64_t reply_type) override;
  bool forward_call(const std::string& service, const MsgRef& request, std::uint64_t id) override;
  // A slot of the topic's segment while another host reads it.
  plr_msg* loan(const std::string& topic, std::size_t capacity, std::uint8_t** data) override;

  // Counters for telemetry: messages out (sent_in_place: from a loaned slot,
  // sent_copied: copied into a slot once) and in, invalid ones dropped.
  nlohmann::json stats() const;
  // The first topic or service of this host that other hosts cannot reach
  // (its segment could not be made, e.g. /dev/shm full), if any: a host
  // without it must not run as if it had it.
  std::string first_error() const;

  struct Outgoing;
  struct Incoming;
  struct Server;
  struct Client;

 private:
  void export_topic(const std::string& topic, std::uint64_t type_id, std::uint32_t version);
  void import_topic(const std::string& topic, std::uint64_t type_id);
  void serve(const std::string& service, std::uint64_t request_type, std::uint64_t reply_type);
  void read_remote_topic(Incoming* in);
  void serve_loop(Server* server);
  void reply_loop(Client* client);
  void reply_loop_body(Client* client);
  // Drops the clients whose server died once their thread is done: each
  // keeps the dead server's segment mapped, and its pages stay taken in
  // /dev/shm until then (a host restarted every few minutes filled it).
  void reap_retired();
  // The host to call `service` on: of the hosts serving it, the one with
  // the fewest of our calls waiting; nullptr when none does.
  std::shared_ptr<Client> client_for(const std::string& service);

  Bus& bus_;
  const PipelineConfig& config_;
  std::string host_;
  std::vector<std::string> peers_;  // the other hosts
  std::string run_id_;
  std::string name_;

  mutable std::mutex m_;
  std::string first_error_;  // under m_
  std::map<std::string, std::unique_ptr<Outgoing>> outgoing_;
  std::map<std::string, std::unique_ptr<Incoming>> incoming_;
  std::map<std::string, std::unique_ptr<Server>> servers_;
  // By service, then by host. A host found not serving a service is looked
  // at again after a while (it may start to, or be restarted).
  std::map<std::string, std::map<std::string, std::shared_ptr<Client>>> clients_;
  std::map<std::pair<std::string, std::string>, std::chrono::steady_clock::time_point> absent_;
  std::vector<std::shared_ptr<Client>> retired_;  // clients whose server died, not yet joined
  std::atomic<bool> stop_{false};

  std::atomic<std::uint64_t> sent_{0};
  std::atomic<std::uint64_t> received_{0};
  std::atomic<std::uint64_t> invalid_{0};
  std::atomic<std::uint64_t> send_failures_{0};
  std::atomic<std::uint64_t> loan_fallbacks_{0};

  NodeThread node_thread_;  // last: stops first, before the maps it works on
};

}  // namespace plr::kernel
