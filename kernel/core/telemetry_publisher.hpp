// Publishes the kernel's telemetry (plr.msg.KernelTelemetry: nodes and their
// states, per-topic rates and latencies) on its own bus, topic
// `kernel/telemetry`, once a period: how a monitor plug-in sees the kernel
// without a way around the bus.
#pragma once

#include "bus.hpp"

#include <flatbuffers/flatbuffers.h>

#include <chrono>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <thread>

namespace plr::kernel {

class TelemetryPublisher {
 public:
  using BuildFn = std::function<void(flatbuffers::FlatBufferBuilder&)>;
  static constexpr const char* kTopic = "kernel/telemetry";

  // Advertises the topic as `owner`; the thread publishes what `build` finishes.
  TelemetryPublisher(Bus& bus, Endpoint* owner, BuildFn build,
                     std::chrono::milliseconds period = std::chrono::milliseconds(1000));
  ~TelemetryPublisher();
  TelemetryPublisher(const TelemetryPublisher&) = delete;
  TelemetryPublisher& operator=(const TelemetryPublisher&) = delete;

 private:
  void loop();
  void publish_once();

  Bus& bus_;
  BuildFn build_;
  std::chrono::milliseconds period_;
  std::uint64_t publisher_ = 0;
  std::mutex m_;
  std::condition_variable cv_;
  bool stop_ = false;
  std::thread thread_;
};

}  // namespace plr::kernel
