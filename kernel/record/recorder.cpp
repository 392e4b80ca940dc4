#include "recorder.hpp"

#include "message.hpp"

#include <plr/message.hpp>
#include <plr/messages.hpp>
#include <plr/schemas.hpp>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <filesystem>

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

std::string record_part(const std::string& path, int k) {
  if (k == 0) return path;
  const std::filesystem::path p(path);
  return (p.parent_path() / (p.stem().string() + "." + std::to_string(k) + p.extension().string()))
      .string();
}

Expected<std::unique_ptr<Recorder>> Recorder::create(Bus& bus, const std::string& path,
                                                     std::vector<std::string> patterns,
                                                     RecordLimits limits) {
  if (limits.max_bytes < (std::uint64_t{1} << 20))
    return make_error(
        PLR_ERR_INVALID,
        fmt::format("--record-max: {} B is below the least, 1 MiB (a chunk)", limits.max_bytes));
  if (limits.keep < 0 || limits.keep > 1000)
    return make_error(PLR_ERR_INVALID,
                      fmt::format("--record-keep: {} is not 0 to 1000", limits.keep));
  auto writer = mcap::Writer::create(path);
  if (!writer) return writer.error();
  if (patterns.empty()) patterns.push_back("*");
  auto r = std::unique_ptr<Recorder>(
      new Recorder(bus, path, std::move(patterns), limits, std::move(*writer)));
  bus.set_live(r.get(), true);
  bus.attach(r.get());
  return r;
}

Recorder::Recorder(Bus& bus, std::string path, std::vector<std::string> patterns,
                   RecordLimits limits, std::unique_ptr<mcap::Writer> writer)
    : bus_(bus),
      path_(std::move(path)),
      patterns_(std::move(patterns)),
      limits_(limits),
      writer_(std::move(writer)) {}

Status Recorder::next_part() {
  if (auto s = writer_->finish(); !s) return s;
  earlier_messages_ += writer_->messages();
  if (limits_.keep == 0) {
    std::filesystem::remove(path_);
  } else {
    std::error_code ec;  // parts not there yet are fine
    for (int k = limits_.keep - 1; k >= 1; --k)
      std::filesystem::rename(record_part(path_, k), record_part(path_, k + 1), ec);
    std::filesystem::rename(path_, record_part(path_, 1), ec);
    if (ec) return make_error(PLR_ERR_INTERNAL, fmt::format("record: {}: {}", path_, ec.message()));
  }
  auto writer = mcap::Writer::create(path_);
  if (!writer) return writer.error();
  writer_ = std::move(*writer);
  // The same ids in the same order: the topics keep their channels.
  for (const auto& c : channel_defs_)
    writer_->add_channel(c.topic, writer_->add_schema(c.schema_name, c.bfbs));
  return {};
}

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
  if (wanted) {
    t->channel = writer_->add_channel(topic, writer_->add_schema(schema->name, schema->bfbs));
    channel_defs_.push_back({topic, schema->name, std::string(schema->bfbs)});
  }
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
    if (r.writer_->messages() > 0 && r.writer_->bytes() + v.size + 64 > r.limits_.max_bytes)
      if (auto s = r.next_part(); !s) {
        spdlog::error("record: {}", s.error().message);
        r.error_ = s;
        return;
      }
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
  return earlier_messages_ + writer_->messages();
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
