// Carries the bus between kernels on different machines over Cyclone DDS.
// Every message is one `plr_dds::Envelope` (dds/envelope.idl) whose payload
// is the bus message's bytes. Exported topics (config `remote.dds.export`)
// go out on DDS topic "plr/topic/<name>" with the topic's QoS; imported ones
// are injected into the local bus. Services a local node provides and that
// are exported are announced; calls nobody here provides go to a live remote
// provider, spread round-robin. Every kernel announces itself (4 Hz) and
// publishes its telemetry (1 Hz) for `plr monitor`. Remote commands arrive on
// "plr/control" and are refused unless remote control is on; results go out
// on "plr/result".
//
// Provider loss policy, per service: when a providing kernel disappears (its
// announce instance is disposed or loses its writer, or no announce for
// kPeerTimeout), a call still waiting on it is re-sent to another live
// provider if the service is declared idempotent (`resend_on_provider_loss`
// patterns; at most once per provider), and otherwise fails at once with
// PLR_ERR_UNAVAILABLE naming the kernel: the bridge cannot know whether the
// lost provider acted on the request.
#pragma once

#include "bus.hpp"
#include "dds_domain.hpp"
#include "node_thread.hpp"
#include "pipeline_config.hpp"

#include <plr/expected.hpp>

#include <dds/dds.h>
#include <nlohmann/json.hpp>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <vector>

struct plr_dds_Envelope;  // generated from dds/envelope.idl

namespace plr::kernel {

class DdsBridge final : public Endpoint, public Link {
 public:
  using TelemetryFn = std::function<std::string()>;
  // Runs a remote command (JSON {"cmd": "swap"|"pause"|"resume", "node", "plugin"}) once allowed.
  using ControlFn = std::function<Status(const nlohmann::json&)>;

  static Expected<std::unique_ptr<DdsBridge>> create(Bus& bus, const PipelineConfig& config,
                                                     std::string kernel_id, TelemetryFn telemetry,
                                                     ControlFn control);
  ~DdsBridge() override;
  DdsBridge(const DdsBridge&) = delete;
  DdsBridge& operator=(const DdsBridge&) = delete;

  NodeThread& node_thread() override { return node_thread_; }
  const std::string& endpoint_name() const override { return name_; }

  Endpoint& link_endpoint() override { return *this; }
  void topic_advertised(const std::string& topic, std::uint64_t type_id,
                        std::uint32_t schema_version) override;
  void topic_subscribed(const std::string& topic, std::uint64_t type_id) override;
  void service_provided(const std::string& service, std::uint64_t request_type,
                        std::uint64_t reply_type) override;
  bool forward_call(const std::string& service, const MsgRef& request, std::uint64_t id) override;

  const std::string& kernel_id() const { return kernel_id_; }
  // Counters for telemetry, and the remote kernels seen.
  nlohmann::json stats() const;

  struct Reader;
  struct Outgoing;
  // A call from a remote kernel to a local provider, and its answer.
  struct ServerCall {
    DdsBridge* bridge;
    std::string caller;
    std::string service;
    std::uint64_t corr;
  };
  void send_reply(const ServerCall& call, plr_status status, const plr_msg* reply,
                  const char* error);

 private:
  DdsBridge(Bus& bus, const PipelineConfig& config, std::string kernel_id, TelemetryFn telemetry,
            ControlFn control);
  Status open();
  void export_topic(const std::string& topic, std::uint64_t type_id, std::uint32_t version);
  void import_topic(const std::string& topic, std::uint64_t type_id);
  void heartbeat_loop();
  void take(Reader* r);
  // A taken sample; bus messages made from it wrap its payload and keep it alive.
  using Sample = std::shared_ptr<::plr_dds_Envelope>;
  plr_msg* payload_message(const Sample& sample);
  void on_data(Reader* r, const Sample& sample);
  void on_request(const Sample& sample);
  void on_reply(const Sample& sample);
  void on_announce(const ::plr_dds_Envelope& e, bool alive);
  void on_command(const ::plr_dds_Envelope& e);
  void expire_peers();
  void peer_gone(const std::string& kernel, const std::string& why);
  struct RemoteCall;
  // Sends `call` to a live provider it has not tried yet; false when there is none.
  bool send_call(RemoteCall call);
  // DDS_RETCODE_OK, or why the sample was not written.
  dds_return_t write(dds_entity_t writer, const std::string& target, const std::string& name,
                     EnvelopeKind kind, std::uint64_t type_id, std::uint32_t version,
                     std::uint64_t corr, std::int32_t status, const std::uint8_t* data,
                     std::size_t size);
  // A reply or error reply. On Cyclone's receive thread it must not wait for
  // acknowledgements, which only that thread takes in: see dds_bridge.cpp.
  void write_reply(const std::string& target, const std::string& service, EnvelopeKind kind,
                   std::uint64_t type_id, std::uint32_t version, std::uint64_t corr,
                   std::int32_t status, const std::uint8_t* data, std::size_t size);
  void invalid(const char* why, const std::string& from);
  Reader* add_reader(dds_entity_t topic, const dds_qos_t* qos, int kind, std::string bus_topic,
                     std::uint64_t type_id);

  Bus& bus_;
  const PipelineConfig& config_;
  std::string kernel_id_;
  std::string name_;
  TelemetryFn telemetry_;
  ControlFn control_;

  dds_entity_t participant_ = 0;
  dds_entity_t announce_writer_ = 0;
  dds_entity_t telemetry_writer_ = 0;
  dds_entity_t result_writer_ = 0;
  dds_entity_t request_writer_ = 0;
  dds_entity_t reply_writer_ = 0;
  dds_entity_t reply_now_writer_ = 0;  // the same topic; gives up instead of waiting

  struct Peer {
    std::chrono::steady_clock::time_point seen;
    std::set<std::string> services;
  };
  struct RemoteCall {
    std::uint64_t bus_id = 0;
    std::string kernel;
    std::string service;
    std::chrono::steady_clock::time_point sent;
    bool resend = false;
    MsgRef request;               // kept only when it may be re-sent
    std::set<std::string> tried;  // providers it went to
  };

  mutable std::mutex m_;
  std::vector<std::unique_ptr<Reader>> readers_;
  std::map<std::string, std::unique_ptr<Outgoing>> outgoing_;
  std::set<std::string> imported_;
  std::set<std::string> served_;  // exported services a local node provides
  std::map<std::string, Peer> peers_;
  std::map<std::uint64_t, RemoteCall> calls_;  // correlation id -> call
  std::uint64_t next_corr_ = 1;
  std::size_t round_robin_ = 0;

  std::atomic<bool> stop_{false};
  std::mutex stop_m_;
  std::condition_variable stop_cv_;
  std::thread heartbeat_;

  std::atomic<std::uint64_t> sent_{0};
  std::atomic<std::uint64_t> received_{0};
  std::atomic<std::uint64_t> invalid_{0};
  std::atomic<std::uint64_t> send_failures_{0};
  std::atomic<std::uint64_t> provider_losses_{0};
  std::atomic<std::uint64_t> resent_{0};
  std::atomic<std::uint64_t> commands_refused_{0};
  std::atomic<std::uint64_t> replies_handed_off_{0};

  NodeThread node_thread_;  // last: stops first, before what it works on
};

}  // namespace plr::kernel
