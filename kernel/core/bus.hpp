// The in-process bus: named topics (publish/subscribe) and services
// (request/reply). Subscribers share the publisher's buffer (zero copy).
// Transports (shared memory, DDS) attach as endpoints like any node.
//
// Overflow policy, per topic (config `topics:`): keep_last drops the oldest
// message queued for a slow subscriber and counts it; reliable makes the
// publisher wait up to `reliable_wait` for room, then drops and counts.
// Every call completes exactly once: reply, provider error, timeout,
// cancellation, or "provider gone".
#pragma once

#include "message.hpp"
#include "node_thread.hpp"
#include "pipeline_config.hpp"

#include <plr/plugin_abi.h>
#include <plr/expected.hpp>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <unordered_map>
#include <vector>

namespace plr::kernel {

// Whatever owns registrations on the bus: a node instance or a transport bridge.
class Endpoint {
 public:
  virtual ~Endpoint() = default;
  virtual NodeThread& node_thread() = 0;
  virtual const std::string& endpoint_name() const = 0;
  // Only live endpoints receive topic messages and new service requests.
  std::atomic<bool> live{false};
};

// A transport to other processes or machines. The bus tells it what local
// nodes publish, subscribe and provide, and hands it calls that no local
// node provides.
class Link {
 public:
  virtual ~Link() = default;
  virtual Endpoint& link_endpoint() = 0;
  // Called without the bus lock, before the publisher learns its id.
  virtual void topic_advertised(const std::string& topic, std::uint64_t type_id,
                                std::uint32_t schema_version) = 0;
  virtual void topic_subscribed(const std::string& topic, std::uint64_t type_id) = 0;
  virtual void service_provided(const std::string& service, std::uint64_t request_type,
                                std::uint64_t reply_type) = 0;
  // Sends call `id` to a remote provider; false when there is none. The link
  // answers through Bus::respond.
  virtual bool forward_call(const std::string& service, const MsgRef& request,
                            std::uint64_t id) = 0;
  // A buffer for the next message a local node publishes on `topic`, in the
  // transport's own memory (a shared-memory slot), or nullptr when the
  // transport does not carry the topic. Called without the bus lock.
  virtual plr_msg* loan(const std::string& /*topic*/, std::size_t /*capacity*/,
                        std::uint8_t** /*data*/) {
    return nullptr;
  }
};

struct TopicStatsSnapshot {
  std::string name;
  std::uint64_t type_id = 0;
  std::uint64_t messages = 0;
  std::uint64_t drops = 0;
  std::uint64_t invalid = 0;
  double rate_hz = 0;
  double latency_mean_us = 0;
  double latency_max_us = 0;
  std::size_t subscribers = 0;
};

struct ServiceInfo {
  std::string name;
  std::vector<std::string> providers;  // endpoint names, live first
};

class Bus {
 public:
  using TopicSettingsFn = std::function<TopicSettings(const std::string&)>;
  explicit Bus(TopicSettingsFn settings = {});
  ~Bus();
  Bus(const Bus&) = delete;
  Bus& operator=(const Bus&) = delete;

  Expected<std::uint64_t> advertise(Endpoint* owner, const std::string& topic,
                                    std::uint64_t type_id, std::uint32_t schema_version);
  // A buffer of `capacity` bytes to build the next message of `publisher` in:
  // a transport's slot when the topic leaves the process (published there
  // without a copy), plain memory otherwise. Null only for an unknown publisher.
  plr_msg* loan(std::uint64_t publisher, std::size_t capacity, std::uint8_t** data);
  // Adopts `msg` (one reference).
  Status publish(std::uint64_t publisher, plr_msg* msg);
  Expected<std::uint64_t> subscribe(Endpoint* owner, const std::string& topic,
                                    std::uint64_t type_id, plr_subscription_fn fn, void* user);
  Status unsubscribe(std::uint64_t subscription);

  // `flags`: PLR_SERVICE_* (plugin_abi.h). A quick service's handler runs
  // on the thread that delivers the request when its node is idle.
  Status provide(Endpoint* owner, const std::string& service, std::uint64_t request_type,
                 std::uint64_t reply_type, plr_service_fn fn, void* user, std::uint32_t flags = 0);
  // Adopts `request`. When this returns OK, `fn` runs exactly once (possibly
  // before call() returns); when it returns an error, never.
  Status call(Endpoint* caller, const std::string& service, std::uint64_t request_type,
              plr_msg* request, std::chrono::nanoseconds timeout, plr_reply_fn fn, void* user,
              std::uint64_t* call_id);
  // Adopts `reply`. Refuses a token already answered, expired or unknown.
  Status respond(std::uint64_t token, plr_status status, plr_msg* reply, const std::string& error);
  Status cancel(std::uint64_t call_id);

  // Makes `fresh` live and `old` not, in one step as seen by every publish and call.
  void swap_live(Endpoint* old, Endpoint* fresh);
  void set_live(Endpoint* e, bool live);
  // Calls still waiting for an answer from `provider`.
  std::size_t pending_for(const Endpoint* provider) const;
  // Drops everything `e` registered (publishers too: an unconfigured node
  // publishes nothing). Calls it provides fail ("provider gone");
  // calls it made complete as cancelled, while its code is still loaded.
  void remove_endpoint(Endpoint* e);

  // Attaches a transport (before nodes start); it is told about what exists
  // already. Calls nobody here provides go to the links in attach order.
  void attach(Link* link);
  void detach(Link* link);

  void count_invalid(const plr_msg* msg);
  std::vector<TopicStatsSnapshot> topic_stats();
  std::vector<ServiceInfo> services() const;
  // The services `provider` offers, by name.
  std::vector<std::string> services_of(const Endpoint* provider) const;
  std::uint64_t invalid_total() const { return invalid_total_.load(); }

  static constexpr std::chrono::milliseconds reliable_wait{1000};

 private:
  struct Topic;
  struct Subscription;
  struct Provider;
  struct Pending;

  Topic& topic_locked(const std::string& name);
  void deliver(const std::shared_ptr<Subscription>& sub, const MsgRef& msg);
  static void drain(const std::shared_ptr<Subscription>& sub);
  bool erase_pending_locked(std::uint64_t id, Pending* out = nullptr);
  void complete(std::uint64_t id, plr_status status, plr_msg* reply, const std::string& error);
  void timer_loop();

  TopicSettingsFn settings_;
  mutable std::mutex m_;
  std::map<std::string, std::unique_ptr<Topic>> topics_;
  struct Publisher {
    Topic* topic;
    const Endpoint* owner;
  };
  std::unordered_map<std::uint64_t, Publisher> publishers_;
  std::unordered_map<std::uint64_t, std::shared_ptr<Subscription>> subscriptions_;
  std::map<std::string, std::vector<Provider>> services_;
  std::unordered_map<std::uint64_t, Pending> pending_;
  std::multimap<std::chrono::steady_clock::time_point, std::uint64_t> deadlines_;
  std::uint64_t next_id_ = 1;
  std::atomic<std::uint64_t> invalid_total_{0};
  std::vector<Link*> links_;  // tried in order for calls: local transports first

  // Reply callbacks running now, per caller (complete() runs them unlocked).
  std::unordered_map<const Endpoint*, std::ptrdiff_t> replying_;
  std::condition_variable replied_;

  std::condition_variable timer_cv_;
  // When the timer thread wakes by itself (max: only when notified).
  std::chrono::steady_clock::time_point timer_wakes_at_ =
      std::chrono::steady_clock::time_point::max();
  bool stop_ = false;
  std::thread timer_;
};

}  // namespace plr::kernel
