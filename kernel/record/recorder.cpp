#include "recorder.hpp"

#include "message.hpp"

#include <plr/message.hpp>
#include <plr/messages.hpp>
#include <plr/schemas.hpp>

#include <spdlog/spdlog.h>

namespace plr::kernel {

bool topic_matches(std::string_view pattern, std::string_view name) {
  const auto star = pattern.find('*');
  if (star == std::string_view::npos) return pattern == name;
  if (!name.starts_with(pattern.substr(0, star))) return false;
  const auto rest = pattern.substr(star + 1);
  for (std::size_t at = star; at <= name.size(); ++at)
    if (topic_matches(rest, name.substr(at))) return true;
  return false;
}

Expected<std::unique_ptr<Recorder>> Recorder::create(Bus& bus, const std::string& path,
                                                     std::vector<std::string> patterns) {
  auto writer = mcap::Writer::create(path);
  if (!writer) return writer.error();
  if (patterns.empty()) patterns.push_back("*");
  auto r =
      std::unique_ptr<Recorder>(new Recorder(bus, path, std::move(patterns), std::move(*writer)));
  bus.set_live(r.get(), true);
  bus.attach(r.get());
  return r;
}

Recorder::Recorder(Bus& bus, std::string path, std::vector<std::string> patterns,
                   std::unique_ptr<mcap::Writer> writer)
    : bus_(bus),
      path_(std::move(path)),
      patterns_(std::move(patterns)),
      writer_(std::move(writer)) {}

Recorder::~Recorder() {
  bus_.detach(this);
  bus_.remove_endpoint(this);
  thread_.drain();
}

void Recorder::topic_advertised(const std::string& topic, std::uint64_t type_id, std::uint32_t) {
  // Without the bus lock and before the publisher can publish: nothing is missed.
  subscribe(topic, type_id);
}

void Recorder::subscribe(const std::string& topic, std::uint64_t type_id) {
  std::lock_guard lock(m_);
  if (!seen_.insert(topic).second) return;
  const bool discovery = topic == kTelemetryTopic;
  bool wanted = false;
  for (const auto& p : patterns_) wanted = wanted || topic_matches(p, topic);
  if (!wanted && !discovery) return;
  const auto* schema = find_schema(type_id);
  if (wanted && schema == nullptr) {
    spdlog::warn("record: topic '{}' not recorded: its type {:016x} has no SDK schema", topic,
                 type_id);
    if (!discovery) return;
    wanted = false;
  }
  auto t = std::make_unique<Topic>(Topic{this, 0, discovery});
  if (wanted)
    t->channel = writer_->add_channel(topic, writer_->add_schema(schema->name, schema->bfbs));
  auto sub = bus_.subscribe(this, topic, type_id, &Recorder::on_message, t.get());
  if (!sub) {
    spdlog::warn("record: topic '{}': {}", topic, sub.error().message);
    return;
  }
  subscriptions_.push_back(*sub);
  topics_[topic] = std::move(t);
}

void Recorder::on_message(void* user, const plr_msg* msg) {
  auto& t = *static_cast<Topic*>(user);
  auto& r = *t.recorder;
  const auto v = msg_view(msg);
  if (t.channel != 0) {
    std::lock_guard lock(r.m_);
    if (!r.error_) return;
    const auto now = static_cast<std::uint64_t>(wall_now_ns());
    if (auto s = r.writer_->write(t.channel, now, static_cast<std::uint64_t>(v.stamp_ns),
                                  {reinterpret_cast<const char*>(v.data), v.size});
        !s) {
      spdlog::error("record: {}", s.error().message);
      r.error_ = s;
    }
  }
  // Other hosts' topics reach this bus only once someone here subscribes:
  // their kernels' telemetry (imported by this very subscription) names them.
  if (t.discovery && verify<msg::KernelTelemetry>(v.data, v.size)) {
    const auto& telemetry = *flatbuffers::GetRoot<msg::KernelTelemetry>(v.data);
    if (telemetry.topics())
      for (const auto* s : *telemetry.topics())
        if (s->name() && s->type_id() != 0) r.subscribe(s->name()->str(), s->type_id());
  }
}

std::uint64_t Recorder::messages() const {
  std::lock_guard lock(m_);
  return writer_->messages();
}

Status Recorder::finish() {
  // Subscriptions made and every delivered message written, on the recorder's thread.
  thread_.drain();
  thread_.run_sync([this] {
    for (auto id : subscriptions_) (void)bus_.unsubscribe(id);
    subscriptions_.clear();
  });
  thread_.drain();
  std::lock_guard lock(m_);
  if (!error_) return error_;
  return writer_->finish();
}

}  // namespace plr::kernel
