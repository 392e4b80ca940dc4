#include "telemetry_publisher.hpp"

#include "message.hpp"

#include <plr/message.hpp>
#include <plr/messages.hpp>

#include <spdlog/spdlog.h>

#include <cstring>

namespace plr::kernel {

TelemetryPublisher::TelemetryPublisher(Bus& bus, Endpoint* owner, BuildFn build,
                                       std::chrono::milliseconds period)
    : bus_(bus), build_(std::move(build)), period_(period) {
  auto id = bus_.advertise(owner, kTopic, MessageTraits<msg::KernelTelemetry>::type_id(),
                           MessageTraits<msg::KernelTelemetry>::schema_version);
  if (!id) {
    spdlog::warn("telemetry: {}", id.error().message);
    return;
  }
  publisher_ = *id;
  thread_ = std::thread([this] { loop(); });
}

TelemetryPublisher::~TelemetryPublisher() {
  {
    std::lock_guard lock(m_);
    stop_ = true;
  }
  cv_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void TelemetryPublisher::loop() {
  std::unique_lock lock(m_);
  while (!cv_.wait_for(lock, period_, [this] { return stop_; })) {
    lock.unlock();
    publish_once();
    lock.lock();
  }
}

void TelemetryPublisher::publish_once() {
  flatbuffers::FlatBufferBuilder fbb;
  build_(fbb);
  std::uint8_t* data = nullptr;
  plr_msg* msg = bus_.loan(publisher_, fbb.GetSize(), &data);
  if (msg == nullptr) return;
  std::memcpy(data, fbb.GetBufferPointer(), fbb.GetSize());
  msg->offset = 0;
  msg->size = fbb.GetSize();
  (void)bus_.publish(publisher_, msg);
}

}  // namespace plr::kernel
