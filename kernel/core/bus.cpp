#include "bus.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <deque>
#include <set>

namespace plr::kernel {

using Clock = std::chrono::steady_clock;

namespace {
// Callers whose reply callbacks this thread is running, innermost last.
thread_local std::vector<const Endpoint*> t_replying;

// A quick service's handler may run on a transport's receive thread, where
// a slow one holds up everything that thread delivers: said once per service.
constexpr auto kQuickBudget = std::chrono::milliseconds(1);

void note_quick_time(const std::string& service, const Endpoint& node, Clock::duration took) {
  if (took <= kQuickBudget) return;
  static std::mutex m;
  static std::set<std::string> warned;
  std::lock_guard lock(m);
  if (warned.insert(service).second)
    spdlog::warn(
        "quick service '{}' of '{}' took {:.1f} ms: it may run on a receive thread, so it should "
        "answer within {} ms (or drop the quick flag)",
        service, node.endpoint_name(), std::chrono::duration<double, std::milli>(took).count(),
        kQuickBudget.count());
}
}  // namespace

struct Bus::Topic {
  std::string name;
  std::uint64_t type_id = 0;
  std::uint32_t schema_version = 0;
  TopicSettings cfg;
  std::vector<std::shared_ptr<Subscription>> subs;
  std::atomic<std::uint64_t> messages{0};
  std::atomic<std::uint64_t> drops{0};
  std::atomic<std::uint64_t> invalid{0};
  std::atomic<std::uint64_t> latency_count{0};
  std::atomic<std::int64_t> latency_sum_ns{0};
  std::atomic<std::int64_t> latency_max_ns{0};
  std::uint64_t sampled_messages = 0;
  Clock::time_point sampled_at = Clock::now();
};

struct Bus::Subscription {
  std::uint64_t id = 0;
  Endpoint* owner = nullptr;
  plr_subscription_fn fn = nullptr;
  void* user = nullptr;
  Topic* topic = nullptr;
  std::mutex m;
  std::condition_variable room;
  std::deque<MsgRef> queue;
  bool scheduled = false;
  bool removed = false;
};

struct Bus::Provider {
  Endpoint* owner = nullptr;
  std::uint64_t request_type = 0;
  std::uint64_t reply_type = 0;
  plr_service_fn fn = nullptr;
  void* user = nullptr;
  bool quick = false;
};

struct Bus::Pending {
  Endpoint* caller = nullptr;
  Endpoint* provider = nullptr;
  plr_reply_fn fn = nullptr;
  void* user = nullptr;
  std::string service;
  Clock::time_point deadline;
  std::chrono::nanoseconds timeout{};
};

Bus::Bus(TopicSettingsFn settings)
    : settings_(std::move(settings)), timer_([this] { timer_loop(); }) {}

Bus::~Bus() {
  {
    std::lock_guard lock(m_);
    stop_ = true;
  }
  timer_cv_.notify_all();
  timer_.join();
  std::vector<std::uint64_t> left;
  {
    std::lock_guard lock(m_);
    for (const auto& [id, p] : pending_) left.push_back(id);
  }
  for (auto id : left) complete(id, PLR_ERR_UNAVAILABLE, nullptr, "bus shut down");
}

Bus::Topic& Bus::topic_locked(const std::string& name) {
  auto& slot = topics_[name];
  if (!slot) {
    slot = std::make_unique<Topic>();
    slot->name = name;
    slot->cfg = settings_ ? settings_(name) : TopicSettings{};
  }
  return *slot;
}

static Error type_mismatch(const std::string& topic, std::uint64_t has, std::uint64_t wants) {
  return make_error(PLR_ERR_INVALID,
                    fmt::format("topic '{}' carries type {:016x}, not {:016x}", topic, has, wants));
}

Expected<std::uint64_t> Bus::advertise(Endpoint* owner, const std::string& topic,
                                       std::uint64_t type_id, std::uint32_t schema_version) {
  std::vector<Link*> links;
  std::uint64_t id = 0;
  {
    std::lock_guard lock(m_);
    Topic& t = topic_locked(topic);
    if (t.type_id != 0 && t.type_id != type_id) return type_mismatch(topic, t.type_id, type_id);
    t.type_id = type_id;
    t.schema_version = schema_version;
    id = next_id_++;
    publishers_[id] = {&t, owner};
    for (auto* l : links_)
      if (owner != &l->link_endpoint()) links.push_back(l);
  }
  // Unlocked, and before the publisher has its id: a link may subscribe here
  // and miss none of the topic's messages (the recorder does).
  for (auto* l : links) l->topic_advertised(topic, type_id, schema_version);
  return id;
}

plr_msg* Bus::loan(std::uint64_t publisher, std::size_t capacity, std::uint8_t** data) {
  std::string name;
  const Topic* topic = nullptr;
  std::vector<Link*> links;
  {
    std::lock_guard lock(m_);
    auto it = publishers_.find(publisher);
    if (it == publishers_.end()) return nullptr;
    topic = it->second.topic;
    name = topic->name;
    links = links_;
  }
  for (auto* l : links) {
    if (plr_msg* m = l->loan(name, capacity, data)) {
      m->loan->topic = topic;
      return m;
    }
  }
  return msg_alloc(capacity, data);
}

Status Bus::publish(std::uint64_t publisher, plr_msg* msg) {
  MsgRef ref(msg);
  std::vector<std::shared_ptr<Subscription>> targets;
  Topic* topic = nullptr;
  {
    std::lock_guard lock(m_);
    auto it = publishers_.find(publisher);
    if (it == publishers_.end())
      return make_error(PLR_ERR_INVALID, fmt::format("publish: unknown publisher {}", publisher));
    Topic& t = *it->second.topic;
    msg->type_id = t.type_id;
    msg->schema_version = t.schema_version;
    msg->stamp_ns = wall_now_ns();
    msg->topic = &t;
    topic = &t;
    t.messages.fetch_add(1, std::memory_order_relaxed);
    for (const auto& s : t.subs)
      if (s->owner->live.load(std::memory_order_acquire)) targets.push_back(s);
  }
  // On the publisher's thread, before any reader can see it: the transport
  // sends the loaned bytes in place, and then need not copy them.
  const void* sent_by = nullptr;
  if (msg->loan && msg->origin == nullptr && msg->loan->topic == topic && msg->loan->commit(*msg)) {
    msg->origin = msg->loan->transport;
    sent_by = msg->loan->endpoint;
  }
  for (const auto& s : targets)
    if (s->owner != sent_by) deliver(s, ref);
  return {};
}

void Bus::deliver(const std::shared_ptr<Subscription>& sub, const MsgRef& msg) {
  Topic& t = *sub->topic;
  std::unique_lock lock(sub->m);
  if (sub->removed) return;
  if (sub->queue.size() >= t.cfg.depth) {
    // Waiting on our own thread could never end: the reader is us.
    if (t.cfg.policy == TopicPolicy::Reliable && !sub->owner->node_thread().on_this_thread()) {
      sub->room.wait_for(lock, reliable_wait,
                         [&] { return sub->removed || sub->queue.size() < t.cfg.depth; });
      if (sub->removed) return;
    }
    if (sub->queue.size() >= t.cfg.depth) {
      sub->queue.pop_front();
      t.drops.fetch_add(1, std::memory_order_relaxed);
    }
  }
  sub->queue.push_back(msg);
  if (sub->scheduled) return;
  sub->scheduled = true;
  lock.unlock();
  if (!sub->owner->node_thread().post([sub] { drain(sub); })) {
    std::lock_guard again(sub->m);
    sub->scheduled = false;
  }
}

void Bus::drain(const std::shared_ptr<Subscription>& sub) {
  Topic& t = *sub->topic;
  for (;;) {
    MsgRef m;
    {
      std::lock_guard lock(sub->m);
      if (sub->removed || sub->queue.empty()) {
        sub->scheduled = false;
        return;
      }
      m = std::move(sub->queue.front());
      sub->queue.pop_front();
    }
    sub->room.notify_one();
    const auto latency = wall_now_ns() - m.msg->stamp_ns;
    t.latency_count.fetch_add(1, std::memory_order_relaxed);
    t.latency_sum_ns.fetch_add(latency, std::memory_order_relaxed);
    auto prev = t.latency_max_ns.load(std::memory_order_relaxed);
    while (latency > prev && !t.latency_max_ns.compare_exchange_weak(prev, latency)) {
    }
    sub->fn(sub->user, m.msg);
  }
}

Expected<std::uint64_t> Bus::subscribe(Endpoint* owner, const std::string& topic,
                                       std::uint64_t type_id, plr_subscription_fn fn, void* user) {
  std::lock_guard lock(m_);
  Topic& t = topic_locked(topic);
  if (t.type_id != 0 && t.type_id != type_id) return type_mismatch(topic, t.type_id, type_id);
  t.type_id = type_id;
  auto sub = std::make_shared<Subscription>();
  sub->id = next_id_++;
  sub->owner = owner;
  sub->fn = fn;
  sub->user = user;
  sub->topic = &t;
  t.subs.push_back(sub);
  subscriptions_[sub->id] = sub;
  for (auto* l : links_)
    if (owner != &l->link_endpoint()) l->topic_subscribed(topic, type_id);
  return sub->id;
}

Status Bus::unsubscribe(std::uint64_t subscription) {
  std::shared_ptr<Subscription> sub;
  {
    std::lock_guard lock(m_);
    auto it = subscriptions_.find(subscription);
    if (it == subscriptions_.end())
      return make_error(PLR_ERR_INVALID,
                        fmt::format("unsubscribe: unknown subscription {}", subscription));
    sub = it->second;
    subscriptions_.erase(it);
    std::erase(sub->topic->subs, sub);
  }
  std::lock_guard lock(sub->m);
  sub->removed = true;
  sub->queue.clear();
  sub->room.notify_all();
  return {};
}

Status Bus::provide(Endpoint* owner, const std::string& service, std::uint64_t request_type,
                    std::uint64_t reply_type, plr_service_fn fn, void* user, std::uint32_t flags) {
  if ((flags & ~std::uint32_t{PLR_SERVICE_QUICK}) != 0)
    return make_error(PLR_ERR_INVALID,
                      fmt::format("service '{}': unknown flags {:#x}", service, flags));
  std::lock_guard lock(m_);
  auto& providers = services_[service];
  for (const auto& p : providers) {
    if (p.owner == owner)
      return make_error(PLR_ERR_INVALID,
                        fmt::format("service '{}' is already provided by this node", service));
    if (p.request_type != request_type || p.reply_type != reply_type)
      return make_error(PLR_ERR_INVALID,
                        fmt::format("service '{}' is provided by '{}' with other message types",
                                    service, p.owner->endpoint_name()));
  }
  providers.push_back(
      {owner, request_type, reply_type, fn, user, (flags & PLR_SERVICE_QUICK) != 0});
  for (auto* l : links_)
    if (owner != &l->link_endpoint()) l->service_provided(service, request_type, reply_type);
  return {};
}

Status Bus::call(Endpoint* caller, const std::string& service, std::uint64_t request_type,
                 plr_msg* request, std::chrono::nanoseconds timeout, plr_reply_fn fn, void* user,
                 std::uint64_t* call_id) {
  MsgRef req(request);
  Provider chosen;
  bool remote = false;
  bool wake_timer = false;
  std::vector<Link*> links;
  std::uint64_t id = 0;
  {
    std::lock_guard lock(m_);
    auto it = services_.find(service);
    if (it != services_.end()) {
      for (const auto& p : it->second)
        if (p.owner->live.load(std::memory_order_acquire)) {
          chosen = p;
          break;
        }
    }
    // Nobody here provides it: maybe another process does.
    if (chosen.owner == nullptr)
      for (auto* l : links_)
        if (caller != &l->link_endpoint()) links.push_back(l);
    remote = chosen.owner == nullptr && !links.empty();
    if (chosen.owner == nullptr && !remote)
      return make_error(PLR_ERR_UNAVAILABLE, fmt::format("no provider for service '{}'", service));
    if (!remote && chosen.request_type != request_type)
      return make_error(PLR_ERR_INVALID, fmt::format("service '{}' takes type {:016x}, not {:016x}",
                                                     service, chosen.request_type, request_type));
    id = next_id_++;
    const auto deadline = Clock::now() + timeout;
    pending_[id] = {caller, chosen.owner, fn, user, service, deadline, timeout};
    // The timer thread keeps sleeping until the time it chose, even when the
    // call it chose it for has completed: wake it only for an earlier
    // deadline, not for every call made after a quiet moment.
    wake_timer = deadline < timer_wakes_at_;
    deadlines_.emplace(deadline, id);
    request->type_id = request_type;
    request->stamp_ns = wall_now_ns();
  }
  if (wake_timer) timer_cv_.notify_one();
  if (call_id) *call_id = id;
  if (remote) {
    for (auto* l : links) {
      {
        std::lock_guard lock(m_);
        auto it = pending_.find(id);
        if (it == pending_.end()) return {};  // answered already
        it->second.provider = &l->link_endpoint();
      }
      if (l->forward_call(service, req, id)) return {};
    }
    std::lock_guard lock(m_);
    // Still ours to withdraw unless a link answered in the meantime.
    if (erase_pending_locked(id))
      return make_error(PLR_ERR_UNAVAILABLE, fmt::format("no provider for service '{}'", service));
    return {};
  }
  const auto run = [fn = chosen.fn, user = chosen.user, req, id] { fn(user, req.msg, id); };
  NodeThread& thread = chosen.owner->node_thread();
  const bool posted = chosen.quick ? thread.dispatch([run, service, owner = chosen.owner] {
    const auto start = Clock::now();
    run();
    note_quick_time(service, *owner, Clock::now() - start);
  })
                                   : thread.post(run);
  if (!posted)
    complete(
        id, PLR_ERR_UNAVAILABLE, nullptr,
        fmt::format("provider '{}' of '{}' is overloaded", chosen.owner->endpoint_name(), service));
  return {};
}

bool Bus::erase_pending_locked(std::uint64_t id, Pending* out) {
  auto it = pending_.find(id);
  if (it == pending_.end()) return false;
  auto [b, e] = deadlines_.equal_range(it->second.deadline);
  for (auto d = b; d != e; ++d)
    if (d->second == id) {
      deadlines_.erase(d);
      break;
    }
  if (out) *out = std::move(it->second);
  pending_.erase(it);
  return true;
}

Status Bus::respond(std::uint64_t token, plr_status status, plr_msg* reply,
                    const std::string& error) {
  bool known = false;
  {
    std::lock_guard lock(m_);
    known = pending_.count(token) != 0;
  }
  if (!known) {
    if (reply) msg_release(reply);
    return make_error(
        PLR_ERR_INVALID,
        fmt::format("respond: call {} was already answered, expired or unknown", token));
  }
  complete(token, status, reply, error);
  return {};
}

Status Bus::cancel(std::uint64_t call_id) {
  complete(call_id, PLR_ERR_CANCELLED, nullptr, "cancelled by the caller");
  return {};
}

void Bus::complete(std::uint64_t id, plr_status status, plr_msg* reply, const std::string& error) {
  MsgRef r(reply);
  Pending p;
  {
    std::lock_guard lock(m_);
    if (!erase_pending_locked(id, &p)) return;  // someone else completed it first
    ++replying_[p.caller];
  }
  t_replying.push_back(p.caller);
  if (status == PLR_OK && r.msg == nullptr)
    p.fn(p.user, PLR_ERR_INTERNAL, nullptr, "provider answered without a reply");
  else
    p.fn(p.user, status, status == PLR_OK ? r.msg : nullptr,
         status == PLR_OK ? nullptr : (error.empty() ? "call failed" : error.c_str()));
  t_replying.pop_back();
  {
    std::lock_guard lock(m_);
    if (--replying_[p.caller] == 0) replying_.erase(p.caller);
  }
  replied_.notify_all();
}

void Bus::timer_loop() {
  std::unique_lock lock(m_);
  while (!stop_) {
    if (deadlines_.empty()) {
      timer_wakes_at_ = Clock::time_point::max();
      timer_cv_.wait(lock);
      continue;
    }
    const auto first = deadlines_.begin()->first;
    if (Clock::now() < first) {
      timer_wakes_at_ = first;
      timer_cv_.wait_until(lock, first);
      continue;
    }
    std::vector<std::pair<std::uint64_t, std::string>> expired;
    const auto now = Clock::now();
    for (auto it = deadlines_.begin(); it != deadlines_.end() && it->first <= now; ++it) {
      const auto& p = pending_.at(it->second);
      expired.emplace_back(
          it->second,
          fmt::format("call to '{}' timed out after {} ms", p.service,
                      std::chrono::duration_cast<std::chrono::milliseconds>(p.timeout).count()));
    }
    lock.unlock();
    for (const auto& [id, why] : expired) complete(id, PLR_ERR_TIMEOUT, nullptr, why);
    lock.lock();
  }
}

void Bus::swap_live(Endpoint* old, Endpoint* fresh) {
  std::lock_guard lock(m_);
  fresh->live.store(true, std::memory_order_release);
  old->live.store(false, std::memory_order_release);
}

void Bus::set_live(Endpoint* e, bool live) {
  std::lock_guard lock(m_);
  e->live.store(live, std::memory_order_release);
}

std::size_t Bus::pending_for(const Endpoint* provider) const {
  std::lock_guard lock(m_);
  return std::count_if(pending_.begin(), pending_.end(),
                       [&](const auto& kv) { return kv.second.provider == provider; });
}

void Bus::remove_endpoint(Endpoint* e) {
  std::vector<std::shared_ptr<Subscription>> removed;
  std::vector<std::pair<std::uint64_t, std::string>> failed;
  std::vector<std::uint64_t> cancelled;
  {
    std::lock_guard lock(m_);
    for (auto it = subscriptions_.begin(); it != subscriptions_.end();) {
      if (it->second->owner == e) {
        std::erase(it->second->topic->subs, it->second);
        removed.push_back(it->second);
        it = subscriptions_.erase(it);
      } else {
        ++it;
      }
    }
    std::erase_if(publishers_, [&](const auto& p) { return p.second.owner == e; });
    for (auto& [name, providers] : services_)
      std::erase_if(providers, [&](const Provider& p) { return p.owner == e; });
    for (const auto& [id, p] : pending_) {
      if (p.provider == e)
        failed.emplace_back(id, fmt::format("provider '{}' of '{}' went away before answering",
                                            e->endpoint_name(), p.service));
      else if (p.caller == e)
        cancelled.push_back(id);
    }
  }
  for (const auto& s : removed) {
    std::lock_guard lock(s->m);
    s->removed = true;
    s->queue.clear();
    s->room.notify_all();
  }
  for (const auto& [id, why] : failed) complete(id, PLR_ERR_UNAVAILABLE, nullptr, why);
  for (auto id : cancelled) complete(id, PLR_ERR_CANCELLED, nullptr, "caller went away");
  // A reply taken off pending_ just before may still be running e's
  // callback on a transport's thread: e's code must outlive it. Callbacks
  // this thread is inside of itself are not waited for.
  const auto own = std::count(t_replying.begin(), t_replying.end(), e);
  std::unique_lock lock(m_);
  replied_.wait(lock, [&] {
    const auto it = replying_.find(e);
    return it == replying_.end() || it->second <= own;
  });
}

void Bus::attach(Link* link) {
  std::vector<std::tuple<std::string, std::uint64_t, std::uint32_t, bool>> topics;
  std::vector<std::tuple<std::string, std::uint64_t, std::uint64_t>> services;
  {
    std::lock_guard lock(m_);
    links_.push_back(link);
    for (const auto& [name, t] : topics_)
      topics.emplace_back(name, t->type_id, t->schema_version, !t->subs.empty());
    for (const auto& [name, providers] : services_)
      if (!providers.empty())
        services.emplace_back(name, providers.front().request_type, providers.front().reply_type);
  }
  for (const auto& [name, type, version, subscribed] : topics) {
    link->topic_advertised(name, type, version);
    if (subscribed) link->topic_subscribed(name, type);
  }
  for (const auto& [name, request, reply] : services) link->service_provided(name, request, reply);
}

void Bus::detach(Link* link) {
  std::lock_guard lock(m_);
  std::erase(links_, link);
}

void Bus::count_invalid(const plr_msg* msg) {
  invalid_total_.fetch_add(1, std::memory_order_relaxed);
  if (msg && msg->topic)
    static_cast<Topic*>(const_cast<void*>(msg->topic))
        ->invalid.fetch_add(1, std::memory_order_relaxed);
}

std::vector<TopicStatsSnapshot> Bus::topic_stats() {
  std::lock_guard lock(m_);
  std::vector<TopicStatsSnapshot> out;
  const auto now = Clock::now();
  for (auto& [name, t] : topics_) {
    TopicStatsSnapshot s;
    s.name = name;
    s.type_id = t->type_id;
    s.messages = t->messages.load();
    s.drops = t->drops.load();
    s.invalid = t->invalid.load();
    s.subscribers = t->subs.size();
    const double dt = std::chrono::duration<double>(now - t->sampled_at).count();
    if (dt > 0) s.rate_hz = static_cast<double>(s.messages - t->sampled_messages) / dt;
    t->sampled_messages = s.messages;
    t->sampled_at = now;
    const auto n = t->latency_count.load();
    if (n) s.latency_mean_us = static_cast<double>(t->latency_sum_ns.load()) / n / 1e3;
    s.latency_max_us = static_cast<double>(t->latency_max_ns.load()) / 1e3;
    out.push_back(std::move(s));
  }
  return out;
}

std::vector<ServiceInfo> Bus::services() const {
  std::lock_guard lock(m_);
  std::vector<ServiceInfo> out;
  for (const auto& [name, providers] : services_) {
    ServiceInfo info{name, {}};
    for (const auto& p : providers) info.providers.push_back(p.owner->endpoint_name());
    out.push_back(std::move(info));
  }
  return out;
}

std::vector<std::string> Bus::services_of(const Endpoint* provider) const {
  std::lock_guard lock(m_);
  std::vector<std::string> out;
  for (const auto& [name, providers] : services_)
    for (const auto& p : providers)
      if (p.owner == provider) {
        out.push_back(name);
        break;
      }
  return out;
}

}  // namespace plr::kernel
