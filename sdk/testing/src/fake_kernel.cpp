#include <plr/testing/fake_kernel.hpp>

#include <nlohmann/json.hpp>

#include <dlfcn.h>

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <limits>
#include <stdexcept>

namespace plr::testing {
namespace detail {
namespace {

// A fake_service_error() accepts requests of every type.
constexpr std::uint64_t kAnyType = 0;

// Marks a live buffer, so a foreign or freed pointer aborts instead of corrupting.
constexpr std::uint64_t kMsgMagic = 0x706c725f6d736721ull;

[[noreturn]] void die(const std::string& why) {
  std::fprintf(stderr, "plr::testing::FakeKernel: %s\n", why.c_str());
  std::abort();
}

// The fake kernel's buffer behind the opaque plr_msg. Not named plr_msg, so a
// test binary may link the real kernel too.
struct Msg {
  std::uint64_t magic = kMsgMagic;
  std::atomic<std::int32_t> refs{1};
  std::vector<std::uint8_t> storage;
  std::size_t offset = 0;
  std::size_t size = 0;
  std::uint64_t type_id = 0;
  std::uint32_t schema_version = 0;
  std::int64_t stamp_ns = 0;
  std::shared_ptr<std::atomic<std::int64_t>> live;  // the kernel's counter, may outlive it
};

Msg* msg_of(const plr_msg* m) {
  auto* msg = reinterpret_cast<Msg*>(const_cast<plr_msg*>(m));
  if (msg->magic != kMsgMagic) die("not a live message buffer (released twice, or foreign)");
  return msg;
}
plr_msg* to_plr(Msg* m) {
  return reinterpret_cast<plr_msg*>(m);
}

void retain(const plr_msg* m) {
  if (m == nullptr) return;
  if (msg_of(m)->refs.fetch_add(1) <= 0) die("msg_retain on a released buffer");
}
void release(const plr_msg* m) {
  if (m == nullptr) return;
  Msg* msg = msg_of(m);
  const auto before = msg->refs.fetch_sub(1);
  if (before <= 0) die("msg_release on a released buffer");
  if (before == 1) {
    msg->magic = 0;
    msg->live->fetch_sub(1);
    delete msg;
  }
}

Sample sample_of(const Msg& m, std::string from, std::string topic) {
  const auto* p = m.storage.data() + m.offset;
  return Sample{std::move(from),  std::move(topic), m.type_id,
                m.schema_version, m.stamp_ns,       {p, p + m.size}};
}

const char* level_name(plr_log_level l) {
  switch (l) {
    case PLR_LOG_DEBUG:
      return "debug";
    case PLR_LOG_INFO:
      return "info";
    case PLR_LOG_WARN:
      return "warn";
    case PLR_LOG_ERROR:
      return "error";
  }
  return "?";
}

}  // namespace

using FakeFn = std::function<Status(const Sample&, flatbuffers::FlatBufferBuilder&)>;

struct Slot {
  struct Kernel* k = nullptr;
  plr_host_api api{};
  std::string name;
  std::string params_json;
  std::map<std::string, std::string> remaps;
  plr_node_api node{};
  const std::type_info* type = nullptr;
  void* object = nullptr;
  std::atomic<NodeState> state{NodeState::Unconfigured};
  bool alive = false;

  std::string resolve(const char* n) const {
    auto it = remaps.find(n);
    return it == remaps.end() ? std::string(n) : it->second;
  }
  bool active() const { return state.load() == NodeState::Active; }
};

struct Kernel {
  struct Pub {
    Slot* owner;
    std::string topic;
    std::uint64_t type_id;
    std::uint32_t schema_version;
  };
  struct Sub {
    Slot* owner;
    std::string topic;
    plr_subscription_fn fn;
    void* user;
  };
  struct Provider {
    Slot* owner;  // nullptr for a fake service
    std::uint64_t request_type;
    std::uint64_t reply_type;
    plr_service_fn fn;
    void* user;
    FakeFn fake;
  };
  struct Pending {
    Slot* caller;
    std::string service;
    std::uint64_t reply_type;
    std::int64_t deadline_ns;
    plr_reply_fn fn;
    void* user;
    Slot* provider;          // who was asked
    bool delivered = false;  // the provider holds the token
  };
  struct Work {
    bool request;  // a service request (id = call id) or a topic message (id = subscription)
    std::uint64_t id;
    Msg* msg;  // one reference
  };

  KernelOptions options;
  mutable std::mutex m;
  std::condition_variable published;  // a sample was recorded
  std::atomic<std::int64_t> now{0};
  std::shared_ptr<std::atomic<std::int64_t>> live = std::make_shared<std::atomic<std::int64_t>>(0);
  std::vector<std::unique_ptr<Slot>> slots;
  Slot* test = nullptr;
  std::vector<void*> libraries;
  std::map<std::string, std::uint64_t> topic_types;
  std::map<std::uint64_t, Pub> pubs;
  std::map<std::uint64_t, Sub> subs;
  // Several nodes may provide a service (as during a hot swap); the first
  // active one answers.
  std::map<std::string, std::vector<Provider>> services;
  std::map<std::uint64_t, Pending> pending;  // by call id, which is also the token
  std::deque<Work> queue;
  std::vector<Sample> samples;
  std::map<std::string, std::vector<Sample>> requests;
  std::vector<LogLine> logs;
  std::vector<Rejection> rejections;
  std::vector<Offer> offers;
  std::uint64_t next_id = 1;

  Msg* alloc(std::size_t capacity) {
    auto* msg = new Msg;
    msg->storage.resize(capacity);
    msg->size = capacity;
    msg->live = live;
    live->fetch_add(1);
    return msg;
  }

  void log(const std::string& node, plr_log_level level, std::string text) {
    if (level >= options.echo_level)
      std::fprintf(stderr, "[%s] %s: %s\n", node.c_str(), level_name(level), text.c_str());
    std::lock_guard lock(m);
    logs.push_back({node, level, std::move(text)});
  }

  // Runs a completion outside the lock; the kernel's reference to `reply` is
  // released afterwards, so a caller keeps it only by retaining it.
  static void finish(const Pending& p, plr_status status, Msg* reply, const std::string& error) {
    p.fn(p.user, status, status == PLR_OK ? to_plr(reply) : nullptr,
         status == PLR_OK ? nullptr : error.c_str());
    release(to_plr(reply));
  }

  // Completes call `id` if still pending; false when it already completed.
  bool complete(std::uint64_t id, plr_status status, Msg* reply, const std::string& error) {
    std::unique_lock lock(m);
    auto it = pending.find(id);
    if (it == pending.end()) {
      lock.unlock();
      release(to_plr(reply));
      return false;
    }
    Pending p = std::move(it->second);
    pending.erase(it);
    lock.unlock();
    if (reply != nullptr) {
      reply->type_id = p.reply_type;
      reply->stamp_ns = now.load();
    }
    finish(p, status, reply, error);
    return true;
  }

  // Drops everything `s` registered: an unconfigured node holds nothing.
  void drop_registrations(Slot* s) {
    std::lock_guard lock(m);
    std::erase_if(pubs, [&](const auto& e) { return e.second.owner == s; });
    std::erase_if(subs, [&](const auto& e) { return e.second.owner == s; });
    for (auto& [name, providers] : services)
      std::erase_if(providers, [&](const Provider& p) { return p.owner == s; });
    std::erase_if(services, [](const auto& e) { return e.second.empty(); });
  }

  // Fails what a node being destroyed still has in flight, while its code is loaded.
  void fail_in_flight(Slot* s) {
    std::vector<std::pair<std::uint64_t, plr_status>> ids;
    {
      std::lock_guard lock(m);
      for (const auto& [id, p] : pending) {
        if (p.caller == s)
          ids.emplace_back(id, PLR_ERR_CANCELLED);
        else if (p.provider == s)
          ids.emplace_back(id, PLR_ERR_UNAVAILABLE);
      }
    }
    for (auto [id, status] : ids)
      complete(id, status, nullptr,
               status == PLR_ERR_CANCELLED ? "caller destroyed" : "provider gone");
  }

  // Runs what `s` accepted while active and has not run yet, in order: a
  // node's thread in the kernel runs it before the node's deactivate hook.
  void deliver_accepted(Slot* s);

  plr_status call(Slot* s, const char* service_name, std::uint64_t request_type, plr_msg* request,
                  std::size_t offset, std::size_t size, std::int64_t timeout_ns, plr_reply_fn fn,
                  void* user, std::uint64_t* call_id,
                  std::string* error = nullptr);  // receives why a call is refused
  // Times out one call whose deadline passed, else runs the front of the queue.
  bool spin_once();
  bool run_front();
};

namespace {

Slot* slot_of(void* ctx) {
  return static_cast<Slot*>(ctx);
}

// Checks and trims a filled buffer handed back by a node; adopts it either way.
bool seal(plr_msg* m, std::size_t offset, std::size_t size, Msg** out) {
  if (m == nullptr) return false;
  Msg* msg = msg_of(m);
  if (offset > msg->storage.size() || size > msg->storage.size() - offset) {
    release(m);
    return false;
  }
  msg->offset = offset;
  msg->size = size;
  *out = msg;
  return true;
}

plr_msg* h_msg_alloc(void* ctx, std::size_t capacity, std::uint8_t** data) {
  Msg* msg = slot_of(ctx)->k->alloc(capacity);
  *data = msg->storage.data();
  return to_plr(msg);
}

plr_msg_view h_msg_view(const plr_msg* m) {
  if (m == nullptr) return {};
  const Msg* msg = msg_of(m);
  return {msg->storage.data() + msg->offset, msg->size, msg->type_id, msg->schema_version,
          msg->stamp_ns};
}

void h_reject(void* ctx, const plr_msg*, const char* reason) {
  Slot* s = slot_of(ctx);
  s->k->log(s->name, PLR_LOG_WARN, std::string("rejected a message: ") + reason);
  std::lock_guard lock(s->k->m);
  s->k->rejections.push_back({s->name, reason});
}

// A topic keeps the type it was first used with: false, and logged, for
// another one (`lock` holds k.m and is released then).
bool type_fits(Kernel& k, std::unique_lock<std::mutex>& lock, const Slot& s,
               const std::string& topic, std::uint64_t type_id, const char* what) {
  const auto [it, fresh] = k.topic_types.emplace(topic, type_id);
  if (fresh || it->second == type_id) return true;
  lock.unlock();
  k.log(s.name, PLR_LOG_ERROR,
        std::string(what) + " '" + topic + "': type differs from the topic's");
  return false;
}

plr_status h_advertise(void* ctx, const char* topic, std::uint64_t type_id,
                       std::uint32_t schema_version, std::uint64_t* publisher) {
  Slot* s = slot_of(ctx);
  Kernel& k = *s->k;
  const std::string name = s->resolve(topic);
  std::unique_lock lock(k.m);
  if (!type_fits(k, lock, *s, name, type_id, "advertise")) return PLR_ERR_INVALID;
  *publisher = k.next_id++;
  k.pubs.emplace(*publisher, Kernel::Pub{s, name, type_id, schema_version});
  k.offers.push_back({s->name, PLR_PORT_TOPIC, name, type_id, 0});
  return PLR_OK;
}

plr_msg* h_loan(void* ctx, std::uint64_t publisher, std::size_t capacity, std::uint8_t** data) {
  Slot* s = slot_of(ctx);
  {
    std::lock_guard lock(s->k->m);
    auto it = s->k->pubs.find(publisher);
    if (it == s->k->pubs.end() || it->second.owner != s) return nullptr;
  }
  return h_msg_alloc(ctx, capacity, data);
}

plr_status publish_as(Kernel& k, const std::string& from, const std::string& topic,
                      std::uint64_t type_id, std::uint32_t schema_version, Msg* msg) {
  msg->type_id = type_id;
  msg->schema_version = schema_version;
  msg->stamp_ns = k.now.load();
  {
    std::lock_guard lock(k.m);
    k.samples.push_back(sample_of(*msg, from, topic));
    for (const auto& [id, sub] : k.subs) {
      if (sub.topic != topic || !sub.owner->active()) continue;
      retain(to_plr(msg));
      k.queue.push_back({false, id, msg});
    }
  }
  k.published.notify_all();
  release(to_plr(msg));
  return PLR_OK;
}

plr_status h_publish(void* ctx, std::uint64_t publisher, plr_msg* m, std::size_t offset,
                     std::size_t size) {
  Slot* s = slot_of(ctx);
  Kernel& k = *s->k;
  Msg* msg = nullptr;
  if (!seal(m, offset, size, &msg)) return PLR_ERR_INVALID;
  std::unique_lock lock(k.m);
  auto it = k.pubs.find(publisher);
  if (it == k.pubs.end() || it->second.owner != s) {
    lock.unlock();
    release(m);
    return PLR_ERR_INVALID;
  }
  const Kernel::Pub pub = it->second;
  lock.unlock();
  return publish_as(k, s->name, pub.topic, pub.type_id, pub.schema_version, msg);
}

plr_status h_subscribe(void* ctx, const char* topic, std::uint64_t type_id, plr_subscription_fn fn,
                       void* user, std::uint64_t* subscription) {
  Slot* s = slot_of(ctx);
  Kernel& k = *s->k;
  const std::string name = s->resolve(topic);
  std::unique_lock lock(k.m);
  if (!type_fits(k, lock, *s, name, type_id, "subscribe")) return PLR_ERR_INVALID;
  *subscription = k.next_id++;
  k.subs.emplace(*subscription, Kernel::Sub{s, name, fn, user});
  return PLR_OK;
}

plr_status h_unsubscribe(void* ctx, std::uint64_t subscription) {
  Slot* s = slot_of(ctx);
  std::lock_guard lock(s->k->m);
  auto it = s->k->subs.find(subscription);
  if (it == s->k->subs.end() || it->second.owner != s) return PLR_ERR_INVALID;
  s->k->subs.erase(it);
  return PLR_OK;
}

// Quick services are delivered like the others, on the node's thread: a
// kernel may always do that.
plr_status h_provide_flags(void* ctx, const char* service, std::uint64_t request_type,
                           std::uint64_t reply_type, std::uint32_t, plr_service_fn fn, void* user,
                           std::uint32_t flags) {
  Slot* s = slot_of(ctx);
  if ((flags & ~std::uint32_t{PLR_SERVICE_QUICK}) != 0) {
    s->k->log(s->name, PLR_LOG_ERROR, "provide: unknown service flags");
    return PLR_ERR_INVALID;
  }
  Kernel& k = *s->k;
  const std::string name = s->resolve(service);
  std::unique_lock lock(k.m);
  auto& providers = k.services[name];
  for (const auto& p : providers) {
    std::string error;
    if (p.owner == s)
      error = "service '" + name + "' is already provided by this node";
    else if (p.request_type != request_type || p.reply_type != reply_type)
      error = "service '" + name + "' is provided by '" + (p.owner ? p.owner->name : "the test") +
              "' with other message types";
    if (error.empty()) continue;
    lock.unlock();
    k.log(s->name, PLR_LOG_ERROR, error);
    return PLR_ERR_INVALID;
  }
  providers.push_back({s, request_type, reply_type, fn, user, {}});
  k.offers.push_back({s->name, PLR_PORT_SERVICE, name, request_type, reply_type});
  return PLR_OK;
}

plr_status h_provide(void* ctx, const char* service, std::uint64_t request_type,
                     std::uint64_t reply_type, std::uint32_t version, plr_service_fn fn,
                     void* user) {
  return h_provide_flags(ctx, service, request_type, reply_type, version, fn, user, 0);
}

plr_status h_respond(void* ctx, std::uint64_t token, plr_status status, plr_msg* reply,
                     std::size_t offset, std::size_t size, const char* error) {
  Slot* s = slot_of(ctx);
  Kernel& k = *s->k;
  Msg* msg = nullptr;
  const bool has_reply = seal(reply, offset, size, &msg);
  {
    std::lock_guard lock(k.m);
    auto it = k.pending.find(token);
    if (it == k.pending.end() || it->second.provider != s || !it->second.delivered) {
      release(to_plr(msg));
      return PLR_ERR_INVALID;  // answered already, expired, or never ours
    }
  }
  if (status == PLR_OK && !has_reply) {
    k.complete(token, PLR_ERR_INTERNAL, nullptr, "provider answered without a valid reply buffer");
    return PLR_ERR_INVALID;
  }
  if (status != PLR_OK) {
    release(to_plr(msg));
    msg = nullptr;
  }
  k.complete(token, status, msg, error != nullptr && *error ? error : "provider failed");
  return PLR_OK;
}

plr_status h_call(void* ctx, const char* service, std::uint64_t request_type, std::uint32_t,
                  plr_msg* request, std::size_t offset, std::size_t size, std::int64_t timeout_ns,
                  plr_reply_fn fn, void* user, std::uint64_t* call_id) {
  Slot* s = slot_of(ctx);
  return s->k->call(s, service, request_type, request, offset, size, timeout_ns, fn, user, call_id);
}

plr_status h_cancel(void* ctx, std::uint64_t call) {
  Slot* s = slot_of(ctx);
  {
    std::lock_guard lock(s->k->m);
    auto it = s->k->pending.find(call);
    if (it == s->k->pending.end() || it->second.caller != s) return PLR_ERR_INVALID;
  }
  s->k->complete(call, PLR_ERR_CANCELLED, nullptr, "cancelled");
  return PLR_OK;
}

const char* h_params_json(void* ctx) {
  return slot_of(ctx)->params_json.c_str();
}
const char* h_node_name(void* ctx) {
  return slot_of(ctx)->name.c_str();
}
void h_log(void* ctx, plr_log_level level, const char* message) {
  slot_of(ctx)->k->log(slot_of(ctx)->name, level, message);
}
std::int64_t h_now_ns(void* ctx) {
  return slot_of(ctx)->k->now.load();
}

plr_host_api host_api(Slot* s) {
  return {PLR_ABI_MAJOR,   PLR_ABI_MINOR, s,
          &h_msg_alloc,    &retain,       &release,
          &h_msg_view,     &h_reject,     &h_advertise,
          &h_loan,         &h_publish,    &h_subscribe,
          &h_unsubscribe,  &h_provide,    &h_respond,
          &h_call,         &h_cancel,     &h_params_json,
          &h_node_name,    &h_log,        &h_now_ns,
          &h_provide_flags};
}

}  // namespace

plr_status Kernel::call(Slot* s, const char* service_name, std::uint64_t request_type,
                        plr_msg* request, std::size_t offset, std::size_t size,
                        std::int64_t timeout_ns, plr_reply_fn fn, void* user,
                        std::uint64_t* call_id, std::string* error) {
  Msg* msg = nullptr;
  if (fn == nullptr) {
    release(request);
    return PLR_ERR_INVALID;
  }
  if (!seal(request, offset, size, &msg)) return PLR_ERR_INVALID;
  msg->type_id = request_type;
  msg->stamp_ns = now.load();
  const std::string service = s->resolve(service_name);

  std::unique_lock lock(m);
  const std::uint64_t id = next_id++;
  requests[service].push_back(sample_of(*msg, s->name, service));
  const std::int64_t t = now.load();
  const std::int64_t deadline = timeout_ns > std::numeric_limits<std::int64_t>::max() - t
                                    ? std::numeric_limits<std::int64_t>::max()
                                    : t + timeout_ns;
  Pending p{s, service, 0, deadline, fn, user, nullptr};
  const Provider* chosen = nullptr;
  if (auto it = services.find(service); it != services.end())
    for (const auto& candidate : it->second)
      if (candidate.owner == nullptr || candidate.owner->active()) {
        chosen = &candidate;
        break;
      }
  // Refused calls never complete: the caller learns it from the status.
  if (chosen == nullptr ||
      (chosen->request_type != kAnyType && chosen->request_type != request_type)) {
    lock.unlock();
    release(to_plr(msg));
    if (chosen == nullptr) {
      if (error != nullptr) *error = "no provider for service '" + service + "'";
      return PLR_ERR_UNAVAILABLE;
    }
    if (error != nullptr) *error = "service '" + service + "' takes another request type";
    return PLR_ERR_INVALID;
  }
  *call_id = id;
  p.reply_type = chosen->reply_type;
  if (chosen->owner == nullptr) {
    // A fake service answers now, on the caller's thread.
    FakeFn fake = chosen->fake;
    lock.unlock();
    const Sample req = sample_of(*msg, s->name, service);
    release(to_plr(msg));
    flatbuffers::FlatBufferBuilder fbb;
    Status result = fake(req, fbb);
    if (!result) {
      finish(p, result.error().code, nullptr, result.error().message);
      return PLR_OK;
    }
    Msg* reply = alloc(fbb.GetSize());
    std::memcpy(reply->storage.data(), fbb.GetBufferPointer(), fbb.GetSize());
    reply->type_id = p.reply_type;
    reply->stamp_ns = now.load();
    finish(p, PLR_OK, reply, {});
    return PLR_OK;
  }
  p.provider = chosen->owner;
  pending.emplace(id, std::move(p));
  queue.push_back({true, id, msg});
  return PLR_OK;
}

void Kernel::deliver_accepted(Slot* s) {
  std::unique_lock lock(m);
  std::deque<Work> mine;
  for (auto it = queue.begin(); it != queue.end();) {
    const bool for_s = it->request ? pending.count(it->id) && pending.at(it->id).provider == s
                                   : subs.count(it->id) && subs.at(it->id).owner == s;
    if (for_s) {
      mine.push_back(*it);
      it = queue.erase(it);
    } else {
      ++it;
    }
  }
  // Run through the front of the queue, one at a time, as spin() would.
  queue.insert(queue.begin(), mine.begin(), mine.end());
  const std::size_t n = mine.size();
  lock.unlock();
  for (std::size_t i = 0; i < n; ++i) run_front();
}

bool Kernel::spin_once() {
  {
    std::unique_lock lock(m);
    const std::int64_t t = now.load();
    for (const auto& [id, p] : pending) {
      if (p.deadline_ns > t) continue;
      const std::uint64_t expired = id;
      const std::string text = "service '" + p.service + "': timed out";
      lock.unlock();
      complete(expired, PLR_ERR_TIMEOUT, nullptr, text);
      return true;
    }
  }
  return run_front();
}

bool Kernel::run_front() {
  std::unique_lock lock(m);
  if (queue.empty()) return false;
  Work w = queue.front();
  queue.pop_front();
  if (!w.request) {
    auto it = subs.find(w.id);
    if (it == subs.end() || !it->second.owner->active()) {
      lock.unlock();
      release(to_plr(w.msg));
      return true;
    }
    const Sub sub = it->second;
    lock.unlock();
    sub.fn(sub.user, to_plr(w.msg));
    release(to_plr(w.msg));
    return true;
  }
  auto p = pending.find(w.id);
  if (p == pending.end()) {  // timed out or cancelled before delivery
    lock.unlock();
    release(to_plr(w.msg));
    return true;
  }
  const Provider* provider = nullptr;
  if (auto svc = services.find(p->second.service); svc != services.end())
    for (const auto& candidate : svc->second)
      if (candidate.owner == p->second.provider) provider = &candidate;
  if (provider == nullptr || !p->second.provider->active()) {
    const std::string text = "service '" + p->second.service + "': provider gone";
    lock.unlock();
    release(to_plr(w.msg));
    complete(w.id, PLR_ERR_UNAVAILABLE, nullptr, text);
    return true;
  }
  p->second.delivered = true;
  const plr_service_fn fn = provider->fn;
  void* user = provider->user;
  lock.unlock();
  fn(user, to_plr(w.msg), w.id);
  release(to_plr(w.msg));
  return true;
}

CallState::~CallState() {
  release(reply);
}

}  // namespace detail

using detail::Kernel;
using detail::Slot;

// --- NodeHandle -------------------------------------------------------------

Status NodeHandle::transition(plr_status (*fn)(void*, char*, std::size_t), NodeState from,
                              NodeState to, const char* what) {
  if (!slot_->alive) return make_error(PLR_ERR_STATE, std::string(what) + ": node destroyed");
  char err[512] = {0};
  const plr_status s = fn(slot_->object, err, sizeof err);
  err[sizeof err - 1] = '\0';
  if (s != PLR_OK) {
    // A node that fails to configure stays unconfigured and keeps nothing.
    if (to == NodeState::Configured && from == NodeState::Unconfigured &&
        slot_->state.load() == NodeState::Unconfigured)
      kernel_->drop_registrations(slot_);
    return make_error(s, err);
  }
  if (slot_->state.load() == from) slot_->state = to;
  if (to == NodeState::Unconfigured) kernel_->drop_registrations(slot_);
  return {};
}

Status NodeHandle::configure() {
  return transition(slot_->node.configure, NodeState::Unconfigured, NodeState::Configured,
                    "configure");
}
Status NodeHandle::activate() {
  return transition(slot_->node.activate, NodeState::Configured, NodeState::Active, "activate");
}
Status NodeHandle::deactivate() {
  if (slot_->alive && slot_->active()) kernel_->deliver_accepted(slot_);
  return transition(slot_->node.deactivate, NodeState::Active, NodeState::Configured, "deactivate");
}
Status NodeHandle::cleanup() {
  return transition(slot_->node.cleanup, NodeState::Configured, NodeState::Unconfigured, "cleanup");
}

void NodeHandle::destroy() {
  if (!slot_->alive) return;
  if (state() == NodeState::Active) (void)deactivate();
  if (state() == NodeState::Configured) (void)cleanup();
  kernel_->fail_in_flight(slot_);
  kernel_->drop_registrations(slot_);
  slot_->node.destroy(slot_->object);
  slot_->object = nullptr;
  slot_->alive = false;
  slot_->state = NodeState::Unconfigured;
}

NodeState NodeHandle::state() const {
  return slot_->state.load();
}
bool NodeHandle::alive() const {
  return slot_->alive;
}
const std::string& NodeHandle::name() const {
  return slot_->name;
}

std::size_t NodeHandle::pending_calls() const {
  std::lock_guard lock(kernel_->m);
  return std::count_if(kernel_->pending.begin(), kernel_->pending.end(),
                       [&](const auto& e) { return e.second.caller == slot_; });
}

std::size_t NodeHandle::unanswered_requests() const {
  std::lock_guard lock(kernel_->m);
  return std::count_if(kernel_->pending.begin(), kernel_->pending.end(), [&](const auto& e) {
    return e.second.provider == slot_ && e.second.delivered;
  });
}

void* NodeHandle::object_as(const std::type_info& type) const {
  if (slot_->type == nullptr || *slot_->type != type || !slot_->alive)
    detail::die("NodeHandle::get<" + std::string(type.name()) + ">() on node '" + slot_->name +
                "', which is not a live node of that type");
  return slot_->object;
}

// --- FakeKernel -------------------------------------------------------------

FakeKernel::FakeKernel(KernelOptions options) : k_(std::make_unique<Kernel>()) {
  k_->options = options;
  k_->now = options.start_ns;
  auto test = std::make_unique<Slot>();
  test->k = k_.get();
  test->api = detail::host_api(test.get());
  test->name = "test";
  test->params_json = "{}";
  test->state = NodeState::Active;
  k_->test = test.get();
  k_->slots.push_back(std::move(test));
}

FakeKernel::~FakeKernel() {
  for (auto it = k_->slots.rbegin(); it != k_->slots.rend(); ++it)
    if ((*it)->alive) NodeHandle(k_.get(), it->get()).destroy();
  k_->fail_in_flight(k_->test);
  for (const auto& w : k_->queue) detail::release(detail::to_plr(w.msg));
  k_->queue.clear();
  for (void* lib : k_->libraries) dlclose(lib);
}

Expected<PluginRef> FakeKernel::load(const std::string& path) {
  void* lib = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (lib == nullptr) return make_error(PLR_ERR_INVALID, path + ": dlopen failed: " + dlerror());
  auto entry = reinterpret_cast<plr_plugin_entry_fn>(dlsym(lib, PLR_ENTRY_SYMBOL));
  const plr_plugin_descriptor* d = entry != nullptr ? entry() : nullptr;
  std::string error;
  if (entry == nullptr)
    error = path + ": no entry point '" PLR_ENTRY_SYMBOL "'";
  else if (d == nullptr)
    error = path + ": entry point returned no descriptor";
  else if (d->abi_major != PLR_ABI_MAJOR)
    error = path + ": built for SDK ABI " + std::to_string(d->abi_major) + ", kernel speaks " +
            std::to_string(PLR_ABI_MAJOR);
  else if (d->name == nullptr || d->node.create == nullptr || d->node.destroy == nullptr ||
           d->node.configure == nullptr || d->node.activate == nullptr ||
           d->node.deactivate == nullptr || d->node.cleanup == nullptr)
    error = path + ": descriptor lacks its name or a life-cycle function";
  if (!error.empty()) {
    dlclose(lib);
    return make_error(PLR_ERR_INVALID, error);
  }
  k_->libraries.push_back(lib);
  auto declared = reinterpret_cast<plr_interface_fn>(dlsym(lib, PLR_INTERFACE_SYMBOL));
  return PluginRef{d, path, declared != nullptr ? declared() : nullptr};
}

Expected<NodeHandle> FakeKernel::create(const PluginRef& plugin, NodeOptions options) {
  if (options.name.empty() && plugin.descriptor->name != nullptr)
    options.name = plugin.descriptor->name;
  try {
    return add_node(plugin.descriptor->node, nullptr, std::move(options));
  } catch (const std::exception& e) {
    return make_error(PLR_ERR_INVALID, plugin.path + ": " + e.what());
  }
}

Expected<NodeHandle> FakeKernel::load_node(const std::string& path, NodeOptions options) {
  auto plugin = load(path);
  if (!plugin) return plugin.error();
  return create(*plugin, std::move(options));
}

NodeHandle FakeKernel::add_node(const plr_node_api& api, const std::type_info* type,
                                NodeOptions options) {
  if (options.name.empty()) options.name = "node";
  const auto params = nlohmann::json::parse(options.params_json, nullptr, false);
  if (!params.is_object())
    throw std::invalid_argument("node '" + options.name +
                                "': params_json is not a JSON object: " + options.params_json);
  for (const auto& s : k_->slots)
    if (s->alive && s->name == options.name)
      throw std::invalid_argument("node '" + options.name + "': name already in use");
  auto slot = std::make_unique<Slot>();
  slot->k = k_.get();
  slot->api = detail::host_api(slot.get());
  slot->name = std::move(options.name);
  slot->params_json = std::move(options.params_json);
  slot->remaps = std::move(options.remaps);
  slot->node = api;
  slot->type = type;
  slot->object = api.create(&slot->api);
  if (slot->object == nullptr)
    throw std::runtime_error("node '" + slot->name + "': create() returned no node");
  slot->alive = true;
  Slot* s = slot.get();
  std::lock_guard lock(k_->m);
  k_->slots.push_back(std::move(slot));
  return NodeHandle(k_.get(), s);
}

std::size_t FakeKernel::spin() {
  std::size_t n = 0;
  while (k_->spin_once()) ++n;
  return n;
}
bool FakeKernel::spin_once() {
  return k_->spin_once();
}

std::int64_t FakeKernel::now_ns() const {
  return k_->now.load();
}
void FakeKernel::set_now(std::int64_t ns) {
  k_->now = ns;
}
void FakeKernel::advance(std::chrono::nanoseconds d) {
  k_->now += d.count();
}

Status FakeKernel::publish_raw(const std::string& topic, std::uint64_t type_id,
                               std::uint32_t schema_version, const std::uint8_t* data,
                               std::size_t size) {
  {
    std::lock_guard lock(k_->m);
    auto [it, fresh] = k_->topic_types.emplace(topic, type_id);
    if (!fresh && it->second != type_id)
      return make_error(PLR_ERR_INVALID, "publish '" + topic + "': type differs from the topic's");
  }
  detail::Msg* msg = k_->alloc(size);
  if (size > 0) std::memcpy(msg->storage.data(), data, size);
  detail::publish_as(*k_, "test", topic, type_id, schema_version, msg);
  return {};
}

std::vector<Sample> FakeKernel::published(const std::string& topic) const {
  std::lock_guard lock(k_->m);
  std::vector<Sample> out;
  for (const auto& s : k_->samples)
    if (s.topic == topic) out.push_back(s);
  return out;
}

bool FakeKernel::wait_published(const std::string& topic, std::size_t n,
                                std::chrono::milliseconds timeout) {
  std::unique_lock lock(k_->m);
  return k_->published.wait_for(lock, timeout, [&] {
    return static_cast<std::size_t>(
               std::count_if(k_->samples.begin(), k_->samples.end(),
                             [&](const Sample& s) { return s.topic == topic; })) >= n;
  });
}

void FakeKernel::clear_published() {
  std::lock_guard lock(k_->m);
  k_->samples.clear();
}

std::size_t FakeKernel::subscribers(const std::string& topic) const {
  std::lock_guard lock(k_->m);
  return std::count_if(k_->subs.begin(), k_->subs.end(),
                       [&](const auto& e) { return e.second.topic == topic; });
}

std::size_t FakeKernel::publishers(const std::string& topic) const {
  std::lock_guard lock(k_->m);
  return std::count_if(k_->pubs.begin(), k_->pubs.end(),
                       [&](const auto& e) { return e.second.topic == topic; });
}

void FakeKernel::add_fake_service(const std::string& service, std::uint64_t request_type,
                                  std::uint64_t reply_type, detail::FakeFn fn) {
  std::lock_guard lock(k_->m);
  auto& providers = k_->services[service];
  if (!providers.empty())
    throw std::invalid_argument("fake_service '" + service + "': already provided");
  providers.push_back({nullptr, request_type, reply_type, nullptr, nullptr, std::move(fn)});
}

void FakeKernel::fake_service_error(const std::string& service, plr_status code,
                                    const std::string& message) {
  // Any request type: the call fails before its bytes matter.
  add_fake_service(service, detail::kAnyType, detail::kAnyType,
                   [code, message](const Sample&, flatbuffers::FlatBufferBuilder&) -> Status {
                     return make_error(code, message);
                   });
}

std::vector<Sample> FakeKernel::requests(const std::string& service) const {
  std::lock_guard lock(k_->m);
  auto it = k_->requests.find(service);
  return it == k_->requests.end() ? std::vector<Sample>{} : it->second;
}

bool FakeKernel::has_provider(const std::string& service) const {
  std::lock_guard lock(k_->m);
  return k_->services.count(service) > 0;
}

std::vector<Offer> FakeKernel::offers() const {
  std::lock_guard lock(k_->m);
  return k_->offers;
}

std::shared_ptr<detail::CallState> FakeKernel::start_call(
    const std::string& service, std::uint64_t request_type, std::uint64_t, std::uint32_t,
    const flatbuffers::FlatBufferBuilder& request, std::chrono::nanoseconds timeout) {
  auto state = std::make_shared<detail::CallState>();
  state->api = &k_->test->api;
  detail::Msg* msg = k_->alloc(request.GetSize());
  std::memcpy(msg->storage.data(), request.GetBufferPointer(), request.GetSize());
  auto* holder = new std::shared_ptr<detail::CallState>(state);
  const auto done = [](void* user, plr_status status, const plr_msg* reply, const char* error) {
    std::unique_ptr<std::shared_ptr<detail::CallState>> h(
        static_cast<std::shared_ptr<detail::CallState>*>(user));
    auto& s = **h;
    detail::retain(reply);
    std::lock_guard lock(s.m);
    s.done = true;
    s.status = status;
    s.error = error != nullptr ? error : "";
    s.reply = reply;
  };
  std::uint64_t id = 0;
  std::string error;
  const plr_status s = k_->call(k_->test, service.c_str(), request_type, detail::to_plr(msg), 0,
                                request.GetSize(), timeout.count(), done, holder, &id, &error);
  if (s != PLR_OK) {
    delete holder;
    std::lock_guard lock(state->m);
    state->done = true;
    state->status = s;
    state->error = error;
  }
  return state;
}

std::int64_t FakeKernel::live_messages() const {
  return k_->live->load();
}

std::size_t FakeKernel::pending_calls() const {
  std::lock_guard lock(k_->m);
  return k_->pending.size();
}

std::vector<LogLine> FakeKernel::logs() const {
  std::lock_guard lock(k_->m);
  return k_->logs;
}

std::vector<Rejection> FakeKernel::rejections() const {
  std::lock_guard lock(k_->m);
  return k_->rejections;
}

const plr_host_api* FakeKernel::test_api() const {
  return &k_->test->api;
}

}  // namespace plr::testing
