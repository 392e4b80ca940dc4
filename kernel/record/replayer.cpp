#include "replayer.hpp"

#include "message.hpp"

#include <plr/message.hpp>
#include <plr/schemas.hpp>

#include <chrono>
#include <cstring>
#include <map>

namespace plr::kernel {

Expected<std::unique_ptr<Replayer>> Replayer::create(Bus& bus, const std::string& path,
                                                     double speed) {
  if (!(speed >= 0)) return make_error(PLR_ERR_INVALID, "--speed: must be >= 0");
  auto bytes = mcap::load(path);
  if (!bytes) return bytes.error();
  auto r = std::unique_ptr<Replayer>(new Replayer(bus, speed));
  mcap::Contents contents;
  std::map<std::uint16_t, std::uint64_t> publishers;  // channel -> bus publisher
  Status advertised;
  auto read = mcap::read(
      *bytes, path,
      [&](const mcap::MessageRecord& m) {
        auto p = publishers.find(m.channel->id);
        if (p == publishers.end()) {
          const auto schema = contents.schemas.find(m.channel->schema_id);
          if (m.channel->message_encoding != mcap::kEncoding || schema == contents.schemas.end()) {
            if (advertised)
              advertised = make_error(PLR_ERR_INVALID, path + ": channel '" + m.channel->topic +
                                                           "' is not FlatBuffers with a schema");
            return;
          }
          const auto type_id = fnv1a(schema->second.name);
          auto id = bus.advertise(r.get(), m.channel->topic, type_id, 1);
          if (!id) {
            if (advertised) advertised = id.error();
            return;
          }
          p = publishers.emplace(m.channel->id, *id).first;
        }
        r->messages_.push_back({p->second, m.log_time, std::string(m.data)});
      },
      contents);
  if (!read) return read.error();
  if (!advertised) return advertised.error();
  bus.set_live(r.get(), true);
  return r;
}

Replayer::~Replayer() {
  stop_ = true;
  if (player_.joinable()) player_.join();
  bus_.remove_endpoint(this);
  thread_.drain();
}

void Replayer::start() {
  player_ = std::thread([this] { play(); });
}

void Replayer::play() {
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  const std::uint64_t first = messages_.empty() ? 0 : messages_.front().log_time;
  for (const auto& m : messages_) {
    if (stop_) break;
    if (speed_ > 0) {
      const double after_s = static_cast<double>(m.log_time - std::min(m.log_time, first)) * 1e-9;
      const auto due = t0 + std::chrono::duration_cast<Clock::duration>(
                                std::chrono::duration<double>(after_s / speed_));
      while (!stop_ && Clock::now() < due)
        std::this_thread::sleep_for(
            std::min<Clock::duration>(due - Clock::now(), std::chrono::milliseconds(50)));
    }
    std::uint8_t* data = nullptr;
    plr_msg* msg = bus_.loan(m.publisher, m.data.size(), &data);
    if (msg == nullptr) continue;
    std::memcpy(data, m.data.data(), m.data.size());
    msg->offset = 0;
    msg->size = m.data.size();
    if (bus_.publish(m.publisher, msg)) ++published_;
  }
  done_ = true;
}

}  // namespace plr::kernel
