#include "dds_bridge.hpp"

#include "envelope_check.hpp"
#include "slot_size.hpp"

#include <dds/ddsc/dds_statistics.h>
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <unistd.h>
#include <cstdlib>
#include <cstring>
#include <filesystem>

namespace plr::kernel {

namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

// Which DDS topic a reader listens to.
enum ReaderKind { kDataReader, kRequestReader, kReplyReader, kAnnounceReader, kControlReader };

constexpr std::size_t kMaxErrorText = 4096;
// A remote call nobody answered for this long is forgotten (the bus has timed it out).
constexpr auto kForgetCall = 15min;

// Set on Cyclone's threads that run our listeners.
thread_local bool t_on_receive_thread = false;

dds_qos_t* topic_qos(const TopicSettings& t) {
  dds_qos_t* q = dds_create_qos();
  if (t.policy == TopicPolicy::Reliable)
    dds_qset_reliability(q, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  else
    dds_qset_reliability(q, DDS_RELIABILITY_BEST_EFFORT, 0);
  dds_qset_history(
      q, DDS_HISTORY_KEEP_LAST,
      static_cast<std::int32_t>(std::max<std::size_t>(1, std::min<std::size_t>(t.depth, 1 << 16))));
  dds_qset_ignorelocal(q, DDS_IGNORELOCAL_PARTICIPANT);
  return q;
}

// What Cyclone's writers report of themselves: how often one had to wait
// for acknowledgements before it could write (too much unacknowledged) and
// how long, and how many bytes it sent again.
struct WriterTotals {
  std::uint64_t waits = 0, wait_ns = 0, resent_bytes = 0;

  void add(dds_entity_t writer) {
    dds_statistics* s = dds_create_statistics(writer);
    if (s == nullptr) return;
    const auto value = [s](const char* name) -> std::uint64_t {
      const dds_stat_keyvalue* kv = dds_lookup_statistic(s, name);
      if (kv == nullptr) return 0;
      return kv->kind == DDS_STAT_KIND_UINT32 ? kv->u.u32 : kv->u.u64;
    };
    waits += value("throttle_count");
    wait_ns += value("time_throttle");
    resent_bytes += value("rexmit_bytes");
    dds_delete_statistics(s);
  }
};

}  // namespace

struct DdsBridge::Reader {
  DdsBridge* bridge = nullptr;
  std::mutex m;  // Cyclone may call its listener from several receive threads
  ReaderKind kind = kDataReader;
  dds_entity_t reader = 0;
  std::string topic;          // data readers: the bus topic
  std::uint64_t type_id = 0;  // data readers: what local subscribers expect
  std::size_t max_size = 0;
  std::uint64_t publisher = 0;  // local publisher id, once known
  Sample spare;                 // the sample to take into next (under m)
};

struct DdsBridge::Outgoing {
  DdsBridge* bridge = nullptr;
  std::string topic;
  dds_entity_t writer = 0;

  static void on_local(void* user, const plr_msg* msg) {
    auto* self = static_cast<Outgoing*>(user);
    if (msg->origin == self->bridge) return;  // it came from DDS
    const auto v = msg_view(msg);
    self->bridge->write(self->writer, "", self->topic, EnvelopeKind::kTopic, v.type_id,
                        v.schema_version, 0, 0, v.data, v.size);
  }
};

Expected<std::unique_ptr<DdsBridge>> DdsBridge::create(Bus& bus, const PipelineConfig& config,
                                                       std::string kernel_id, TelemetryFn telemetry,
                                                       ControlFn control) {
  std::unique_ptr<DdsBridge> b(
      new DdsBridge(bus, config, std::move(kernel_id), std::move(telemetry), std::move(control)));
  if (auto s = b->open(); !s) return s.error();
  return b;
}

DdsBridge::DdsBridge(Bus& bus, const PipelineConfig& config, std::string kernel_id,
                     TelemetryFn telemetry, ControlFn control)
    : bus_(bus),
      config_(config),
      kernel_id_(std::move(kernel_id)),
      name_("dds@" + kernel_id_),
      telemetry_(std::move(telemetry)),
      control_(std::move(control)),
      node_thread_(name_) {}

Status DdsBridge::open() {
  auto p = open_participant(config_.dds);
  if (!p) return p.error();
  participant_ = *p;
  const auto topic = [&](const char* name) {
    return dds_create_topic(participant_, &plr_dds_Envelope_desc, name, nullptr, nullptr);
  };
  struct Plane {
    const char* name;
    std::int32_t depth;
    bool transient;
    dds_entity_t* writer;      // or null
    int reader;                // ReaderKind, or -1
    dds_entity_t* now_writer;  // or null: a second writer that never blocks
  };
  const Plane planes[] = {
      {kDdsAnnounceTopic, 1, false, &announce_writer_, kAnnounceReader, nullptr},
      {kDdsTelemetryTopic, 1, true, &telemetry_writer_, -1, nullptr},
      {kDdsControlTopic, 0, false, nullptr, kControlReader, nullptr},
      // Kept for late readers: a CLI whose reader matched after the answer still gets it.
      {kDdsResultTopic, 16, true, &result_writer_, -1, nullptr},
      {kDdsRequestTopic, 0, false, &request_writer_, kRequestReader, nullptr},
      {kDdsReplyTopic, 0, false, &reply_writer_, kReplyReader, &reply_now_writer_},
  };
  for (const auto& plane : planes) {
    const dds_entity_t t = topic(plane.name);
    if (t < 0)
      return make_error(PLR_ERR_INTERNAL,
                        fmt::format("dds: topic '{}': {}", plane.name, dds_strretcode(t)));
    dds_qos_t* q = control_qos(plane.depth, plane.transient);
    const dds_entity_t w = plane.writer ? dds_create_writer(participant_, t, q, nullptr) : 0;
    if (plane.writer) *plane.writer = w;
    Reader* r = plane.reader < 0 ? nullptr : add_reader(t, q, plane.reader, "", 0);
    if (plane.now_writer) {
      dds_qset_reliability(q, DDS_RELIABILITY_RELIABLE, 0);
      *plane.now_writer = dds_create_writer(participant_, t, q, nullptr);
    }
    dds_delete_qos(q);
    if (w < 0 || (plane.reader >= 0 && r == nullptr) || (plane.now_writer && *plane.now_writer < 0))
      return make_error(PLR_ERR_INTERNAL,
                        fmt::format("dds: cannot create the endpoints of '{}'", plane.name));
  }
  bus_.set_live(this, true);
  heartbeat_ = std::thread([this] { heartbeat_loop(); });
  spdlog::info("dds: kernel '{}' on domain {} ({})", kernel_id_, config_.dds.domain,
               fmt::join(config_.dds.interfaces, ", "));
  return {};
}

DdsBridge::~DdsBridge() {
  stop_ = true;
  stop_cv_.notify_all();
  if (heartbeat_.joinable()) heartbeat_.join();
  // Deleting a reader waits for its listener to return; none runs after this.
  for (const auto& r : readers_) dds_delete(r->reader);
  // Calls to us fail, calls we made for remote kernels complete (their
  // error replies still go out: the participant is alive until the end).
  bus_.remove_endpoint(this);
  node_thread_.drain();
  // Deleting the participant unregisters our announce: peers drop us at once.
  if (participant_ > 0) dds_delete(participant_);
}

DdsBridge::Reader* DdsBridge::add_reader(dds_entity_t topic, const dds_qos_t* qos, int kind,
                                         std::string bus_topic, std::uint64_t type_id) {
  auto r = std::make_unique<Reader>();
  r->bridge = this;
  r->kind = static_cast<ReaderKind>(kind);
  r->topic = std::move(bus_topic);
  r->type_id = type_id;
  r->max_size = slot_size(config_.topic(r->topic), {type_id});
  // Samples are taken in Cyclone's receive thread: no hand-off to a thread of ours.
  Reader* raw = r.get();
  dds_listener_t* listener = dds_create_listener(raw);
  dds_lset_data_available(listener, [](dds_entity_t, void* arg) {
    t_on_receive_thread = true;
    auto* reader = static_cast<Reader*>(arg);
    if (!reader->bridge->stop_) reader->bridge->take(reader);
  });
  r->reader = dds_create_reader(participant_, topic, qos, listener);
  dds_delete_listener(listener);
  if (r->reader < 0) return nullptr;
  std::lock_guard lock(m_);
  readers_.push_back(std::move(r));
  return raw;
}

// The bus may call these with its lock held: the work happens on our own thread.
void DdsBridge::topic_advertised(const std::string& topic, std::uint64_t type_id,
                                 std::uint32_t version) {
  if (!matches_any(config_.dds.export_patterns, topic)) return;
  node_thread_.post([=, this] { export_topic(topic, type_id, version); });
}

void DdsBridge::topic_subscribed(const std::string& topic, std::uint64_t type_id) {
  if (!matches_any(config_.dds.import_patterns, topic)) return;
  node_thread_.post([=, this] { import_topic(topic, type_id); });
}

void DdsBridge::service_provided(const std::string& service, std::uint64_t, std::uint64_t) {
  if (!matches_any(config_.dds.export_patterns, service)) return;
  std::lock_guard lock(m_);
  served_.insert(service);
}

void DdsBridge::export_topic(const std::string& topic, std::uint64_t type_id, std::uint32_t) {
  {
    std::lock_guard lock(m_);
    if (outgoing_.count(topic)) return;
  }
  const dds_entity_t t = dds_create_topic(participant_, &plr_dds_Envelope_desc,
                                          dds_topic_name(topic).c_str(), nullptr, nullptr);
  dds_qos_t* q = topic_qos(config_.topic(topic));
  const dds_entity_t w = t < 0 ? t : dds_create_writer(participant_, t, q, nullptr);
  dds_delete_qos(q);
  if (w < 0) {
    spdlog::error("dds: cannot export topic '{}': {}", topic, dds_strretcode(w));
    return;
  }
  auto out = std::make_unique<Outgoing>(Outgoing{this, topic, w});
  auto* raw = out.get();
  {
    std::lock_guard lock(m_);
    outgoing_[topic] = std::move(out);
  }
  if (auto s = bus_.subscribe(this, topic, type_id, &Outgoing::on_local, raw); !s)
    spdlog::error("dds: cannot export topic '{}': {}", topic, s.error().message);
}

void DdsBridge::import_topic(const std::string& topic, std::uint64_t type_id) {
  {
    std::lock_guard lock(m_);
    if (!imported_.insert(topic).second) return;
  }
  const dds_entity_t t = dds_create_topic(participant_, &plr_dds_Envelope_desc,
                                          dds_topic_name(topic).c_str(), nullptr, nullptr);
  dds_qos_t* q = topic_qos(config_.topic(topic));
  Reader* r = t < 0 ? nullptr : add_reader(t, q, kDataReader, topic, type_id);
  dds_delete_qos(q);
  if (r == nullptr) spdlog::error("dds: cannot import topic '{}'", topic);
}

void DdsBridge::take(Reader* r) {
  // Samples are taken into memory of our own rather than Cyclone's loan, so
  // that a payload goes on to the bus without another copy (64 KiB: a few
  // microseconds per hop). A sample still referenced by a message is left to
  // it and a fresh one taken next; otherwise the reader's last one is reused,
  // its buffers with it (not a fresh payload buffer per message).
  const auto fresh = [] {
    return Sample(
        static_cast<plr_dds_Envelope*>(dds_alloc(sizeof(plr_dds_Envelope))),
        [](plr_dds_Envelope* e) { dds_sample_free(e, &plr_dds_Envelope_desc, DDS_FREE_ALL); });
  };
  std::lock_guard lock(r->m);
  for (;;) {
    if (r->spare.use_count() != 1) r->spare = fresh();
    const Sample& sample = r->spare;
    void* buffer = sample.get();
    dds_sample_info_t info;
    if (dds_take(r->reader, &buffer, &info, 1, 1) <= 0) return;
    const auto& e = *sample;
    if (!info.valid_data) {
      // A kernel's announce instance without writers: that kernel left.
      if (r->kind == kAnnounceReader && info.instance_state != DDS_IST_ALIVE &&
          bounded_len(e.kernel, kMaxKernelId) <= kMaxKernelId)
        on_announce(e, false);
      continue;
    }
    if (const char* why = envelope_problem(e)) {
      invalid(why, bounded_len(e.kernel, kMaxKernelId) <= kMaxKernelId ? e.kernel : "?");
      continue;
    }
    if (kernel_id_ == e.kernel) continue;
    received_.fetch_add(1, std::memory_order_relaxed);
    switch (r->kind) {
      case kDataReader:
        on_data(r, sample);
        break;
      case kRequestReader:
        on_request(sample);
        break;
      case kReplyReader:
        on_reply(sample);
        break;
      case kAnnounceReader:
        on_announce(e, true);
        break;
      case kControlReader:
        on_command(e);
        break;
    }
  }
}

plr_msg* DdsBridge::payload_message(const Sample& sample) {
  const auto& e = *sample;
  if (e.payload._length > 0)
    return msg_wrap(e.payload._buffer, e.payload._length, e.type_id, e.schema_version, sample,
                    this);
  plr_msg* m = msg_copy(nullptr, 0, e.type_id, e.schema_version, wall_now_ns());
  m->origin = this;
  return m;
}

void DdsBridge::invalid(const char* why, const std::string& from) {
  const auto n = invalid_.fetch_add(1, std::memory_order_relaxed) + 1;
  // Logged sparsely: a flood must not turn into a flood of log lines.
  if ((n & (n - 1)) == 0)
    spdlog::warn("dds: dropped an invalid envelope from '{}': {} ({} so far)", from, why, n);
}

void DdsBridge::on_data(Reader* r, const Sample& sample) {
  const auto& e = *sample;
  if (e.kind != static_cast<std::uint8_t>(EnvelopeKind::kTopic))
    return invalid("not a topic message", e.kernel);
  if (r->topic != e.name) return invalid("topic name differs from its DDS topic", e.kernel);
  if (r->type_id != 0 && e.type_id != r->type_id) return invalid("wrong message type", e.kernel);
  if (e.payload._length > r->max_size)
    return invalid("payload larger than the topic's slot_size", e.kernel);
  if (r->publisher == 0) {
    auto p = bus_.advertise(this, r->topic, e.type_id, e.schema_version);
    if (!p) {
      spdlog::error("dds: topic '{}' from '{}': {}", r->topic, e.kernel, p.error().message);
      return;
    }
    r->publisher = *p;
  }
  plr_msg* m = payload_message(sample);
  (void)bus_.publish(r->publisher, m);
}

namespace {

void on_local_reply(void* user, plr_status status, const plr_msg* reply, const char* error) {
  std::unique_ptr<DdsBridge::ServerCall> call(static_cast<DdsBridge::ServerCall*>(user));
  call->bridge->send_reply(*call, status, reply, error);
}

}  // namespace

void DdsBridge::on_request(const Sample& sample) {
  const auto& e = *sample;
  if (e.kind != static_cast<std::uint8_t>(EnvelopeKind::kRequest))
    return invalid("not a request", e.kernel);
  if (kernel_id_ != e.target) return;  // another provider's
  const std::string service = e.name;
  const auto send_error = [&](plr_status status, const std::string& why) {
    write_reply(e.kernel, service, EnvelopeKind::kError, 0, 0, e.correlation_id, status,
                reinterpret_cast<const std::uint8_t*>(why.data()), why.size());
  };
  bool served = false;
  {
    std::lock_guard lock(m_);
    served = served_.count(service) != 0;
  }
  if (!served)
    return send_error(PLR_ERR_UNAVAILABLE,
                      fmt::format("kernel '{}' does not export service '{}'", kernel_id_, service));
  if (e.type_id == 0 || e.payload._length > slot_size(config_.topic(service), {e.type_id})) {
    invalid("bad request type or size", e.kernel);
    return send_error(PLR_ERR_INVALID, "request refused: bad type or size");
  }
  auto* call = new ServerCall{this, e.kernel, service, e.correlation_id};
  plr_msg* m = payload_message(sample);
  auto s = bus_.call(this, service, e.type_id, m, std::chrono::minutes(10), &on_local_reply, call,
                     nullptr);
  if (!s) {
    delete call;
    send_error(s.error().code, s.error().message);
  }
}

void DdsBridge::send_reply(const ServerCall& c, plr_status status, const plr_msg* reply,
                           const char* error) {
  if (status == PLR_OK) {
    const auto v = msg_view(reply);
    write_reply(c.caller, c.service, EnvelopeKind::kReply, v.type_id, v.schema_version, c.corr,
                PLR_OK, v.data, v.size);
    return;
  }
  const std::string why = error ? error : "call failed";
  write_reply(c.caller, c.service, EnvelopeKind::kError, 0, 0, c.corr, status,
              reinterpret_cast<const std::uint8_t*>(why.data()), why.size());
}

// A reliable writer waits when too much of what it sent is unacknowledged.
// On Cyclone's receive thread (a quick service answering, an error reply)
// that wait would never end early: the acknowledgements arrive on that very
// thread. There the reply goes to a writer that gives up at once instead, and
// what it refuses is written by the bridge's own thread, which may wait.
void DdsBridge::write_reply(const std::string& target, const std::string& service,
                            EnvelopeKind kind, std::uint64_t type_id, std::uint32_t version,
                            std::uint64_t corr, std::int32_t status, const std::uint8_t* data,
                            std::size_t size) {
  if (!t_on_receive_thread) {
    write(reply_writer_, target, service, kind, type_id, version, corr, status, data, size);
    return;
  }
  if (write(reply_now_writer_, target, service, kind, type_id, version, corr, status, data, size) !=
      DDS_RETCODE_TIMEOUT)
    return;
  replies_handed_off_.fetch_add(1, std::memory_order_relaxed);
  (void)node_thread_.post([=, this, bytes = std::vector<std::uint8_t>(data, data + size)] {
    write(reply_writer_, target, service, kind, type_id, version, corr, status, bytes.data(),
          bytes.size());
  });
}

void DdsBridge::on_reply(const Sample& sample) {
  const auto& e = *sample;
  if (kernel_id_ != e.target) return;
  const bool error = e.kind == static_cast<std::uint8_t>(EnvelopeKind::kError);
  if (!error && e.kind != static_cast<std::uint8_t>(EnvelopeKind::kReply))
    return invalid("not a reply", e.kernel);
  RemoteCall call;
  {
    std::lock_guard lock(m_);
    auto it = calls_.find(e.correlation_id);
    if (it == calls_.end()) return;  // answered, failed or forgotten already
    if (it->second.kernel != e.kernel || it->second.service != e.name)
      return invalid("reply from a kernel that was not asked", e.kernel);
    call = std::move(it->second);
    calls_.erase(it);
  }
  if (error) {
    auto status = static_cast<plr_status>(e.status);
    if (status <= PLR_OK || status > PLR_ERR_INTERNAL) status = PLR_ERR_INTERNAL;
    std::string why(reinterpret_cast<const char*>(e.payload._buffer),
                    std::min<std::size_t>(e.payload._length, kMaxErrorText));
    (void)bus_.respond(call.bus_id, status, nullptr,
                       fmt::format("{} (kernel '{}')", why, e.kernel));
    return;
  }
  // Replies carry whatever type the provider set (possibly none); the SDK verifies them.
  if (e.payload._length > slot_size(config_.topic(call.service), {e.type_id})) {
    invalid("reply larger than the service's slot_size", e.kernel);
    (void)bus_.respond(call.bus_id, PLR_ERR_INVALID, nullptr,
                       fmt::format("invalid reply from kernel '{}'", e.kernel));
    return;
  }
  plr_msg* m = payload_message(sample);
  (void)bus_.respond(call.bus_id, PLR_OK, m, "");
}

void DdsBridge::on_announce(const plr_dds_Envelope& e, bool alive) {
  if (!alive) return peer_gone(e.kernel, "left the DDS domain");
  if (e.kind != static_cast<std::uint8_t>(EnvelopeKind::kAnnounce))
    return invalid("not an announce", e.kernel);
  auto services = announce_services(e.payload._buffer, e.payload._length);
  if (!services) return invalid(services.error().message.c_str(), e.kernel);
  std::lock_guard lock(m_);
  auto [it, fresh] = peers_.try_emplace(e.kernel);
  it->second.seen = Clock::now();
  it->second.services = std::move(*services);
  if (fresh) spdlog::info("dds: kernel '{}' joined", e.kernel);
}

void DdsBridge::expire_peers() {
  std::vector<std::string> silent;
  std::vector<RemoteCall> forgotten;
  const auto now = Clock::now();
  {
    std::lock_guard lock(m_);
    for (const auto& [id, p] : peers_)
      if (now - p.seen > kPeerTimeout) silent.push_back(id);
    for (auto it = calls_.begin(); it != calls_.end();)
      it = now - it->second.sent > kForgetCall ? calls_.erase(it) : std::next(it);
  }
  for (const auto& k : silent) peer_gone(k, fmt::format("silent for {} ms", kPeerTimeout.count()));
}

void DdsBridge::peer_gone(const std::string& kernel, const std::string& why) {
  std::vector<RemoteCall> lost;
  {
    std::lock_guard lock(m_);
    if (peers_.erase(kernel) == 0) return;
    for (auto it = calls_.begin(); it != calls_.end();) {
      if (it->second.kernel == kernel) {
        lost.push_back(std::move(it->second));
        it = calls_.erase(it);
      } else {
        ++it;
      }
    }
  }
  spdlog::warn("dds: kernel '{}' {}; {} call(s) to it lost", kernel, why, lost.size());
  for (auto& c : lost) {
    const auto id = c.bus_id;
    const auto service = c.service;
    std::string outcome =
        "the request was not re-sent (the service is not in "
        "remote.dds.resend_on_provider_loss)";
    if (c.resend) {
      if (send_call(std::move(c))) {
        resent_.fetch_add(1, std::memory_order_relaxed);
        spdlog::warn("dds: call to '{}' re-sent after losing kernel '{}'", service, kernel);
        continue;
      }
      outcome = "no other live provider to re-send the request to";
    }
    provider_losses_.fetch_add(1, std::memory_order_relaxed);
    (void)bus_.respond(
        id, PLR_ERR_UNAVAILABLE, nullptr,
        fmt::format("kernel '{}' providing '{}' is gone ({}); {}", kernel, service, why, outcome));
  }
}

bool DdsBridge::send_call(RemoteCall call) {
  std::string target;
  std::uint64_t corr = 0;
  {
    std::lock_guard lock(m_);
    std::vector<const std::string*> live;
    for (const auto& [k, p] : peers_)
      if (p.services.count(call.service) && !call.tried.count(k)) live.push_back(&k);
    if (live.empty()) return false;
    // The provider with the fewest of our calls waiting on it, so a slow or
    // busy one is not handed work while another idles; ties take turns.
    std::map<std::string, std::size_t> waiting;
    for (const auto& [c, pending] : calls_)
      if (pending.service == call.service) ++waiting[pending.kernel];
    const std::size_t start = round_robin_++;
    std::size_t best = live.size();
    for (std::size_t k = 0; k < live.size(); ++k) {
      const std::size_t i = (start + k) % live.size();
      if (best == live.size() || waiting[*live[i]] < waiting[*live[best]]) best = i;
    }
    target = *live[best];
    corr = next_corr_++;
    call.kernel = target;
    call.sent = Clock::now();
    call.tried.insert(target);
    auto& stored = calls_[corr] = call;
    if (!stored.resend) stored.request = MsgRef();  // never re-sent: not kept
  }
  // A fresh correlation id: a late answer from a provider given up on is ignored.
  const auto v = msg_view(call.request.msg);
  if (const auto rc = write(request_writer_, target, call.service, EnvelopeKind::kRequest,
                            v.type_id, v.schema_version, corr, 0, v.data, v.size);
      rc < 0) {
    {
      std::lock_guard lock(m_);
      calls_.erase(corr);
    }
    (void)bus_.respond(call.bus_id, PLR_ERR_UNAVAILABLE, nullptr,
                       fmt::format("service '{}' on kernel '{}': DDS write failed ({})",
                                   call.service, target, dds_strretcode(rc)));
  }
  return true;
}

bool DdsBridge::forward_call(const std::string& service, const MsgRef& request, std::uint64_t id) {
  if (!matches_any(config_.dds.import_patterns, service)) return false;
  // Not before our request writer has met a reader: the request would be lost.
  dds_publication_matched_status_t matched{};
  if (dds_get_publication_matched_status(request_writer_, &matched) < 0 ||
      matched.current_count == 0)
    return false;
  RemoteCall call;
  call.bus_id = id;
  call.service = service;
  call.resend = matches_any(config_.dds.resend_patterns, service);
  call.request = request;
  return send_call(std::move(call));
}

void DdsBridge::on_command(const plr_dds_Envelope& e) {
  if (e.kind != static_cast<std::uint8_t>(EnvelopeKind::kCommand))
    return invalid("not a command", e.kernel);
  if (kernel_id_ != e.target) return;
  const std::string from = e.kernel;
  const auto corr = e.correlation_id;
  const auto result = [this, from, corr](plr_status status, const std::string& text) {
    write(result_writer_, from, "result", EnvelopeKind::kResult, 0, 0, corr, status,
          reinterpret_cast<const std::uint8_t*>(text.data()), text.size());
  };
  auto parsed = remote_command(e.payload._buffer, e.payload._length);
  if (!parsed) {
    invalid(parsed.error().message.c_str(), from);
    return result(PLR_ERR_INVALID, parsed.error().message);
  }
  auto cmd = std::move(*parsed);
  const auto what = cmd.dump();
  if (!config_.dds.allow_remote_control) {
    commands_refused_.fetch_add(1, std::memory_order_relaxed);
    spdlog::warn(
        "dds: refused remote command {} from '{}': remote control is off "
        "(remote.dds.allow_remote_control)",
        what, from);
    return result(PLR_ERR_STATE, fmt::format("kernel '{}' refuses remote control "
                                             "(remote.dds.allow_remote_control is off)",
                                             kernel_id_));
  }
  spdlog::info("dds: remote command {} from '{}'", what, from);
  // Off the receive thread: a swap takes a while and registers on the bus.
  node_thread_.post([this, cmd = std::move(cmd), result] {
    auto s = control_(cmd);
    result(s ? PLR_OK : s.error().code, s ? "ok" : s.error().message);
  });
}

dds_return_t DdsBridge::write(dds_entity_t writer, const std::string& target,
                              const std::string& name, EnvelopeKind kind, std::uint64_t type_id,
                              std::uint32_t version, std::uint64_t corr, std::int32_t status,
                              const std::uint8_t* data, std::size_t size) {
  plr_dds_Envelope e{};
  e.kernel = const_cast<char*>(kernel_id_.c_str());
  e.target = const_cast<char*>(target.c_str());
  e.name = const_cast<char*>(name.c_str());
  e.kind = static_cast<std::uint8_t>(kind);
  e.type_id = type_id;
  e.schema_version = version;
  e.correlation_id = corr;
  e.status = status;
  e.payload._buffer = const_cast<std::uint8_t*>(data);
  e.payload._length = static_cast<std::uint32_t>(size);
  e.payload._maximum = static_cast<std::uint32_t>(size);
  e.payload._release = false;
  const dds_return_t rc = dds_write(writer, &e);
  if (rc == DDS_RETCODE_TIMEOUT && writer == reply_now_writer_) return rc;  // written again later
  (rc < 0 ? send_failures_ : sent_).fetch_add(1, std::memory_order_relaxed);
  return rc;
}

void DdsBridge::heartbeat_loop() {
  const std::string host = hostname();
  auto next_telemetry = Clock::now();
  std::unique_lock lock(stop_m_);
  while (!stop_) {
    nlohmann::json announce = {{"services", nlohmann::json::array()}};
    {
      std::lock_guard l(m_);
      for (const auto& s : served_) announce["services"].push_back(s);
    }
    const auto a = announce.dump();
    write(announce_writer_, "", "announce", EnvelopeKind::kAnnounce, 0, 0, 0, 0,
          reinterpret_cast<const std::uint8_t*>(a.data()), a.size());
    if (Clock::now() >= next_telemetry) {
      next_telemetry += 1s;
      auto t = nlohmann::json::parse(telemetry_(), nullptr, false);
      const nlohmann::json doc = {{"kernel", kernel_id_},
                                  {"hostname", host},
                                  {"pid", ::getpid()},
                                  {"telemetry", std::move(t)}};
      const auto d = doc.dump();
      write(telemetry_writer_, "", "telemetry", EnvelopeKind::kTelemetry, 0, 0, 0, 0,
            reinterpret_cast<const std::uint8_t*>(d.data()), d.size());
    }
    expire_peers();
    stop_cv_.wait_for(lock, 250ms, [this] { return stop_.load(); });
  }
}

nlohmann::json DdsBridge::stats() const {
  nlohmann::json peers = nlohmann::json::array();
  WriterTotals writers;
  for (const dds_entity_t w : {request_writer_, reply_writer_, reply_now_writer_, result_writer_})
    writers.add(w);
  {
    std::lock_guard lock(m_);
    for (const auto& [id, p] : peers_) peers.push_back({{"kernel", id}, {"services", p.services}});
    for (const auto& [topic, out] : outgoing_) writers.add(out->writer);
  }
  return {{"kernel", kernel_id_},
          {"domain", config_.dds.domain},
          {"security", !config_.dds.security_dir.empty()},
          {"remote_control", config_.dds.allow_remote_control},
          {"peers", std::move(peers)},
          {"sent", sent_.load()},
          {"received", received_.load()},
          {"invalid", invalid_.load()},
          {"send_failures", send_failures_.load()},
          {"replies_handed_off", replies_handed_off_.load()},
          {"calls_failed_provider_gone", provider_losses_.load()},
          {"calls_resent_provider_gone", resent_.load()},
          {"commands_refused", commands_refused_.load()},
          {"writer_waits", writers.waits},
          {"writer_wait_ms", writers.wait_ns / 1e6},
          {"resent_bytes", writers.resent_bytes}};
}

}  // namespace plr::kernel
