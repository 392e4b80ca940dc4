#include "shm_bridge.hpp"

#include "segment_config.hpp"

#include <plr/message.hpp>
#include <plr/shm/shm.hpp>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cstring>

namespace plr::kernel {

namespace {

using namespace std::chrono_literals;

// Error replies travel as this type: one status byte, then the reason text.
constexpr std::uint64_t kErrorType = fnv1a("plr.transport.Error");

// Why a message too large for its slots is refused.
std::string too_large(const char* what, const std::string& name, std::size_t size,
                      std::size_t slot) {
  return fmt::format(
      "shm: {} '{}': a message of {} bytes exceeds its {}-byte slots (the bound of its "
      "message type; topics.{}.slot_size sets another)",
      what, name, size, slot, name);
}

bool peer_gone(shm::Error e) {
  return e == shm::Error::kPeerDead || e == shm::Error::kClosed;
}

std::string segment(const std::string& host, const std::string& name) {
  return host + "/" + name;
}

// Keeps a shared-memory sample (and so its slot) alive while a message refers to it.
template <class T>
plr_msg* wrap_sample(T&& holder, const shm::Sample& sample, const void* origin) {
  const auto data = sample.data();
  const auto info = sample.info();
  auto keep = std::make_shared<std::decay_t<T>>(std::forward<T>(holder));
  return msg_wrap(reinterpret_cast<const std::uint8_t*>(data.data()), data.size(), info.type_id,
                  info.schema_version, std::move(keep), origin);
}

}  // namespace

// The segment of an exported topic. Shared with the messages built in its
// slots, which may outlive the bridge's table entry.
struct Writer {
  std::mutex m;  // a shm::Publisher is used by one thread at a time
  shm::Publisher publisher;
  std::atomic<std::uint64_t> in_place{0};  // sent from a loaned slot: no copy
  std::atomic<std::uint64_t> copied{0};    // built elsewhere, copied into a slot once

  explicit Writer(shm::Publisher p) : publisher(std::move(p)) {}
};

// A slot loaned to a local publisher. Committed, it stays held for the
// in-process readers of the same message (they read the slot in place).
struct SlotLoan final : MsgLoan {
  std::shared_ptr<Writer> writer;  // first: outlives the loan and the hold
  std::optional<shm::Loan> loan;
  std::optional<shm::Sample> held;

  bool commit(const plr_msg& m) override {
    if (!loan || m.offset > m.capacity || m.size > m.capacity - m.offset) return false;
    std::lock_guard lock(writer->m);
    auto s = writer->publisher.publish_shared(std::move(*loan), {m.type_id, m.schema_version},
                                              m.offset, m.size);
    loan.reset();
    if (!s) return false;
    held.emplace(std::move(*s));
    writer->in_place.fetch_add(1, std::memory_order_relaxed);
    return true;
  }
};

struct ShmBridge::Outgoing {
  ShmBridge* bridge = nullptr;
  std::string topic;
  std::shared_ptr<Writer> writer;
  shm::MessageType type;
  shm::Timeout wait = shm::kNoWait;
  bool told_too_large = false;  // under writer->m

  // Messages not built in one of our slots: copied into one, once.
  static void on_local(void* user, const plr_msg* msg) {
    auto* self = static_cast<Outgoing*>(user);
    if (msg->origin == self->bridge) return;
    Writer& w = *self->writer;
    std::lock_guard lock(w.m);
    if (w.publisher.subscriber_count() == 0) return;
    const auto v = msg_view(msg);
    auto r = w.publisher.publish_copy(
        self->type, {reinterpret_cast<const std::byte*>(v.data), v.size}, self->wait);
    if (r) {
      w.copied.fetch_add(1, std::memory_order_relaxed);
      return;
    }
    self->bridge->send_failures_.fetch_add(1, std::memory_order_relaxed);
    if (r.error() == shm::Error::kTooLarge && !self->told_too_large) {
      self->told_too_large = true;
      spdlog::error("{}; other hosts do not get it",
                    too_large("topic", self->topic, v.size, w.publisher.config().slot_size));
    }
  }
};

struct ShmBridge::Incoming {
  std::string topic;
  std::uint64_t type_id = 0;
  std::string host;
  std::uint64_t publisher = 0;  // local publisher id, once known
  std::thread thread;
};

struct ShmBridge::Server {
  std::string service;
  std::size_t slot_size = 0;
  std::mutex m;  // the shm server is used by one thread at a time
  std::optional<shm::ServiceServer> server;
  std::thread thread;
};

// Replies are read in place: each message built on one keeps its client,
// and so the segment's mapping, alive (a caller may hold a reply long after
// the server died and the bridge let go of the client).
struct ShmBridge::Client : std::enable_shared_from_this<ShmBridge::Client> {
  std::string service;
  std::string host;
  std::mutex m;
  std::optional<shm::ServiceClient> client;
  std::map<std::uint64_t, std::uint64_t> calls;  // correlation id -> bus call id
  std::atomic<bool> dead{false};
  std::atomic<bool> finished{false};  // its thread is past its last use of the bridge
  std::thread thread;
};

// A reply from a local provider to a remote caller.
struct ServerCall {
  ShmBridge::Server* server;
  shm::ReplyTo to;
};

ShmBridge::ShmBridge(Bus& bus, const PipelineConfig& config, std::string host,
                     std::vector<std::string> hosts, std::string run_id)
    : bus_(bus),
      config_(config),
      host_(std::move(host)),
      run_id_(std::move(run_id)),
      name_("shm@" + host_),
      node_thread_(name_) {
  for (auto& h : hosts)
    if (h != host_) peers_.push_back(std::move(h));
  bus_.set_live(this, true);
}

ShmBridge::~ShmBridge() {
  stop_ = true;
  bus_.remove_endpoint(this);
  node_thread_.drain();
  std::lock_guard lock(m_);
  for (auto& [name, in] : incoming_)
    if (in->thread.joinable()) in->thread.join();
  for (auto& [name, s] : servers_)
    if (s->thread.joinable()) s->thread.join();
  for (auto& [name, by_host] : clients_)
    for (auto& [host, c] : by_host) retired_.push_back(c);
  for (auto& c : retired_)
    if (c->thread.joinable()) c->thread.join();
}

// The bus may call these with its lock held: the work happens on our own thread.
void ShmBridge::topic_advertised(const std::string& topic, std::uint64_t type_id,
                                 std::uint32_t version) {
  if (peers_.empty()) return;
  node_thread_.post([=, this] { export_topic(topic, type_id, version); });
}

void ShmBridge::topic_subscribed(const std::string& topic, std::uint64_t type_id) {
  if (peers_.empty()) return;
  node_thread_.post([=, this] { import_topic(topic, type_id); });
}

void ShmBridge::service_provided(const std::string& service, std::uint64_t request_type,
                                 std::uint64_t reply_type) {
  if (peers_.empty()) return;
  node_thread_.post([=, this] { serve(service, request_type, reply_type); });
}

void ShmBridge::export_topic(const std::string& topic, std::uint64_t type_id,
                             std::uint32_t version) {
  {
    std::lock_guard lock(m_);
    if (outgoing_.count(topic)) return;
  }
  const auto settings = config_.topic(topic);
  auto pub = shm::PublisherBuilder()
                 .run_id(run_id_)
                 .topic(segment(host_, topic))
                 .config(topic_segment_config(settings, type_id))
                 .create();
  if (!pub) {
    const auto e =
        fmt::format("shm: cannot export topic '{}': {}", topic, shm::to_string(pub.error()));
    spdlog::error("{}", e);
    std::lock_guard lock(m_);
    if (first_error_.empty()) first_error_ = e;
    return;
  }
  auto out = std::make_unique<Outgoing>(
      Outgoing{this, topic, std::make_shared<Writer>(std::move(*pub)), {type_id, version}});
  if (settings.policy == TopicPolicy::Reliable) out->wait = Bus::reliable_wait;
  auto* raw = out.get();
  {
    std::lock_guard lock(m_);
    outgoing_[topic] = std::move(out);
  }
  if (auto s = bus_.subscribe(this, topic, type_id, &Outgoing::on_local, raw); !s)
    spdlog::error("shm: cannot export topic '{}': {}", topic, s.error().message);
}

plr_msg* ShmBridge::loan(const std::string& topic, std::size_t capacity, std::uint8_t** data) {
  std::shared_ptr<Writer> w;
  shm::Timeout wait;
  {
    std::lock_guard lock(m_);
    auto it = outgoing_.find(topic);
    if (it == outgoing_.end()) return nullptr;
    w = it->second->writer;
    wait = it->second->wait;
  }
  auto slot = std::make_unique<SlotLoan>();
  {
    std::lock_guard lock(w->m);
    // Nobody in another process reads it: plain memory serves the local readers.
    if (w->publisher.subscriber_count() == 0) return nullptr;
    auto l = w->publisher.loan(capacity, wait);
    if (!l) {
      // Too big for a slot, or none free: plain memory, copied once if sent.
      loan_fallbacks_.fetch_add(1, std::memory_order_relaxed);
      return nullptr;
    }
    slot->loan.emplace(std::move(*l));
  }
  slot->writer = std::move(w);
  slot->transport = this;
  slot->endpoint = static_cast<const Endpoint*>(this);
  *data = reinterpret_cast<std::uint8_t*>(slot->loan->data());
  return msg_loaned(*data, capacity, std::move(slot));
}

void ShmBridge::import_topic(const std::string& topic, std::uint64_t type_id) {
  std::lock_guard lock(m_);
  for (const auto& peer : peers_) {
    const auto key = segment(peer, topic);
    if (incoming_.count(key)) continue;
    auto in = std::make_unique<Incoming>();
    in->topic = topic;
    in->type_id = type_id;
    in->host = peer;
    auto* raw = in.get();
    in->thread = std::thread([this, raw] { read_remote_topic(raw); });
    incoming_[key] = std::move(in);
  }
}

void ShmBridge::read_remote_topic(Incoming* in) {
  // Shared with the messages read from it: a reader may hold one after the
  // publisher died and this thread moved on to its successor's segment.
  std::shared_ptr<shm::Subscriber> sub;
  while (!stop_) {
    if (!sub) {
      auto s =
          shm::SubscriberBuilder().run_id(run_id_).topic(segment(in->host, in->topic)).create();
      if (!s) {
        std::this_thread::sleep_for(20ms);  // its publisher is not up (yet, or again)
        continue;
      }
      sub = std::make_shared<shm::Subscriber>(std::move(*s));
    }
    auto sample = sub->take(100ms);
    if (!sample) {
      if (peer_gone(sample.error())) sub.reset();
      continue;
    }
    const auto info = sample->info();
    if (info.type_id != in->type_id) {
      invalid_.fetch_add(1, std::memory_order_relaxed);
      continue;
    }
    if (in->publisher == 0) {
      auto p = bus_.advertise(this, in->topic, info.type_id, info.schema_version);
      if (!p) {
        spdlog::error("shm: topic '{}' from host '{}': {}", in->topic, in->host, p.error().message);
        continue;
      }
      in->publisher = *p;
    }
    received_.fetch_add(1, std::memory_order_relaxed);
    auto held = std::make_pair(sub, std::move(*sample));
    const shm::Sample& ref = held.second;
    plr_msg* m = wrap_sample(std::move(held), ref, this);
    (void)bus_.publish(in->publisher, m);
  }
}

void ShmBridge::serve(const std::string& service, std::uint64_t request_type,
                      std::uint64_t reply_type) {
  std::lock_guard lock(m_);
  if (servers_.count(service)) return;
  const auto geometry =
      service_segment_config(config_.topic(service), request_type, reply_type, peers_.size() + 1);
  auto created = shm::ServiceServerBuilder()
                     .run_id(run_id_)
                     .service(segment(host_, service))
                     .config(geometry)
                     .create();
  if (!created) {
    const auto e =
        fmt::format("shm: cannot serve '{}': {}", service, shm::to_string(created.error()));
    spdlog::error("{}", e);
    if (first_error_.empty()) first_error_ = e;
    return;
  }
  auto s = std::make_unique<Server>();
  s->service = service;
  s->slot_size = geometry.slot_size;
  s->server.emplace(std::move(*created));
  auto* raw = s.get();
  s->thread = std::thread([this, raw] { serve_loop(raw); });
  servers_[service] = std::move(s);
}

namespace {

void send_error(ShmBridge::Server* server, const shm::ReplyTo& to, plr_status status,
                const std::string& why);

void send_reply(ShmBridge::Server* server, const shm::ReplyTo& to, shm::MessageType type,
                const std::uint8_t* data, std::size_t size) {
  std::unique_lock lock(server->m);
  auto loan = server->server->loan_reply(to, size, 1s);
  if (!loan && loan.error() == shm::Error::kTooLarge && type.type_id != kErrorType) {
    // The caller hears why instead of waiting for its timeout.
    lock.unlock();
    const auto why = too_large("service", server->service, size, server->slot_size);
    spdlog::error("{}", why);
    send_error(server, to, PLR_ERR_INVALID, why);
    return;
  }
  if (!loan) return;  // the caller left or died; nobody is waiting
  std::memcpy(loan->data(), data, size);
  (void)server->server->send_reply(std::move(*loan), to, type, 0, size);
}

void send_error(ShmBridge::Server* server, const shm::ReplyTo& to, plr_status status,
                const std::string& why) {
  std::string payload(1, static_cast<char>(status));
  payload += why;
  payload.resize(std::min(payload.size(), server->slot_size));  // slots of a few bytes
  send_reply(server, to, {kErrorType, 1}, reinterpret_cast<const std::uint8_t*>(payload.data()),
             payload.size());
}

void on_local_reply(void* user, plr_status status, const plr_msg* reply, const char* error) {
  std::unique_ptr<ServerCall> call(static_cast<ServerCall*>(user));
  if (status != PLR_OK) {
    send_error(call->server, call->to, status, error ? error : "call failed");
    return;
  }
  const auto v = msg_view(reply);
  send_reply(call->server, call->to, {v.type_id, v.schema_version}, v.data, v.size);
}

}  // namespace

void ShmBridge::serve_loop(Server* server) {
  while (!stop_) {
    std::optional<shm::Request> request;
    {
      // Short waits: replies from other threads need the server between them.
      std::lock_guard lock(server->m);
      auto r = server->server->take_request(2ms);
      if (r) request.emplace(std::move(*r));
    }
    if (!request) continue;
    received_.fetch_add(1, std::memory_order_relaxed);
    const auto info = request->sample.info();
    const auto to = request->reply_to;
    auto* call = new ServerCall{server, to};
    const auto& sample = request->sample;
    plr_msg* msg = wrap_sample(std::move(request->sample), sample, this);
    auto s =
        bus_.call(this, server->service, info.type_id, msg, 10min, &on_local_reply, call, nullptr);
    if (!s) {
      delete call;
      send_error(server, to, s.error().code, s.error().message);
    }
  }
}

void ShmBridge::reap_retired() {
  std::vector<std::shared_ptr<Client>> done;
  {
    std::lock_guard lock(m_);
    const auto finished = std::partition(retired_.begin(), retired_.end(),
                                         [](const auto& c) { return !c->finished.load(); });
    done.assign(std::make_move_iterator(finished), std::make_move_iterator(retired_.end()));
    retired_.erase(finished, retired_.end());
  }
  // Outside the lock: a thread may still be on its way out of bus calls.
  for (auto& c : done)
    if (c->thread.joinable()) c->thread.join();
}

std::shared_ptr<ShmBridge::Client> ShmBridge::client_for(const std::string& service) {
  // How long a host not serving a service is left alone: opening a segment
  // that is not there costs a system call per call otherwise.
  constexpr auto kLookAgain = 100ms;
  reap_retired();
  const auto now = std::chrono::steady_clock::now();
  std::lock_guard lock(m_);
  auto& by_host = clients_[service];
  std::shared_ptr<Client> best;
  std::size_t best_waiting = 0;
  for (const auto& peer : peers_) {
    auto it = by_host.find(peer);
    if (it != by_host.end() && it->second->dead) {
      retired_.push_back(it->second);
      by_host.erase(it);
      it = by_host.end();
    }
    if (it == by_host.end()) {
      const auto key = std::make_pair(service, peer);
      if (auto a = absent_.find(key); a != absent_.end() && now - a->second < kLookAgain) continue;
      auto c = shm::ServiceClientBuilder().run_id(run_id_).service(segment(peer, service)).create();
      if (!c) {
        absent_[key] = now;
        continue;
      }
      absent_.erase(key);
      auto client = std::make_shared<Client>();
      client->service = service;
      client->host = peer;
      client->client.emplace(std::move(*c));
      auto* raw = client.get();
      client->thread = std::thread([this, raw] { reply_loop(raw); });
      it = by_host.emplace(peer, std::move(client)).first;
    }
    std::size_t waiting = 0;
    {
      std::lock_guard client_lock(it->second->m);
      waiting = it->second->calls.size();
    }
    if (!best || waiting < best_waiting) {
      best = it->second;
      best_waiting = waiting;
    }
  }
  return best;
}

bool ShmBridge::forward_call(const std::string& service, const MsgRef& request, std::uint64_t id) {
  auto client = client_for(service);
  if (!client) return false;
  const auto v = msg_view(request.msg);
  std::lock_guard lock(client->m);
  auto loan = client->client->loan_request(v.size, 1s);
  if (!loan && loan.error() == shm::Error::kTooLarge) {
    (void)bus_.respond(id, PLR_ERR_INVALID, nullptr,
                       too_large("service", service, v.size, client->client->config().slot_size) +
                           fmt::format(" (host '{}')", client->host));
    return true;
  }
  if (!loan) {
    (void)bus_.respond(id, PLR_ERR_UNAVAILABLE, nullptr,
                       fmt::format("service '{}' on host '{}': {}", service, client->host,
                                   shm::to_string(loan.error())));
    return true;
  }
  std::memcpy(loan->data(), v.data, v.size);
  auto corr =
      client->client->send_request(std::move(*loan), {v.type_id, v.schema_version}, 0, v.size);
  if (!corr) {
    (void)bus_.respond(id, PLR_ERR_UNAVAILABLE, nullptr,
                       fmt::format("service '{}' on host '{}': {}", service, client->host,
                                   shm::to_string(corr.error())));
    return true;
  }
  client->calls[*corr] = id;
  sent_.fetch_add(1, std::memory_order_relaxed);
  return true;
}

void ShmBridge::reply_loop(Client* client) {
  reply_loop_body(client);
  client->finished = true;
}

void ShmBridge::reply_loop_body(Client* client) {
  while (!stop_ && !client->dead) {
    auto reply = client->client->take_reply(50ms);
    if (!reply) {
      if (!peer_gone(reply.error())) continue;
      // The providing host died: everything it had in flight fails now.
      std::map<std::uint64_t, std::uint64_t> lost;
      {
        std::lock_guard lock(client->m);
        lost.swap(client->calls);
        client->dead = true;
      }
      for (const auto& [corr, id] : lost)
        (void)bus_.respond(
            id, PLR_ERR_UNAVAILABLE, nullptr,
            fmt::format("host '{}' providing '{}' died", client->host, client->service));
      return;
    }
    const auto info = reply->info();
    std::uint64_t id = 0;
    {
      std::lock_guard lock(client->m);
      auto it = client->calls.find(info.correlation_id);
      if (it == client->calls.end()) continue;  // the caller gave up already
      id = it->second;
      client->calls.erase(it);
    }
    received_.fetch_add(1, std::memory_order_relaxed);
    const auto data = reply->data();
    if (info.type_id == kErrorType) {
      if (data.empty()) {
        invalid_.fetch_add(1, std::memory_order_relaxed);
        (void)bus_.respond(id, PLR_ERR_INVALID, nullptr, "malformed error reply");
        continue;
      }
      const auto status = static_cast<plr_status>(std::to_integer<int>(data[0]));
      std::string why(reinterpret_cast<const char*>(data.data()) + 1, data.size() - 1);
      (void)bus_.respond(id, status == PLR_OK ? PLR_ERR_INTERNAL : status, nullptr, why);
      continue;
    }
    auto held = std::make_pair(client->shared_from_this(), std::move(*reply));
    const shm::Sample& ref = held.second;
    (void)bus_.respond(id, PLR_OK, wrap_sample(std::move(held), ref, this), "");
  }
}

std::string ShmBridge::first_error() const {
  std::lock_guard lock(m_);
  return first_error_;
}

nlohmann::json ShmBridge::stats() const {
  std::uint64_t in_place = 0, copied = 0;
  {
    std::lock_guard lock(m_);
    for (const auto& [topic, out] : outgoing_) {
      in_place += out->writer->in_place.load(std::memory_order_relaxed);
      copied += out->writer->copied.load(std::memory_order_relaxed);
    }
  }
  return {{"host", host_},
          {"run_id", run_id_},
          {"sent", sent_.load() + in_place + copied},
          {"sent_in_place", in_place},
          {"sent_copied", copied},
          {"loan_fallbacks", loan_fallbacks_.load()},
          {"received", received_.load()},
          {"invalid", invalid_.load()},
          {"send_failures", send_failures_.load()}};
}

}  // namespace plr::kernel
