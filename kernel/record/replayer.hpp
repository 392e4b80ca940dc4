// Plays an MCAP recording back onto a bus (`plr replay FILE CONFIG`): each
// channel is advertised as a topic of its schema's type, and the messages
// are published in the file's order, at the recorded pace scaled by `speed`
// (0: as fast as the bus takes them).
#pragma once

#include "bus.hpp"
#include "mcap_reader.hpp"

#include <atomic>
#include <memory>
#include <string>
#include <thread>
#include <vector>

namespace plr::kernel {

class Replayer final : public Endpoint {
 public:
  // Reads and checks the whole file before anything is published.
  static Expected<std::unique_ptr<Replayer>> create(Bus& bus, const std::string& path,
                                                    double speed);
  ~Replayer() override;

  void start();
  bool done() const { return done_; }
  std::uint64_t published() const { return published_; }
  std::size_t size() const { return messages_.size(); }

  NodeThread& node_thread() override { return thread_; }
  const std::string& endpoint_name() const override { return name_; }

 private:
  struct Recorded {
    std::uint64_t publisher;
    std::uint64_t log_time;
    std::string data;
  };
  Replayer(Bus& bus, double speed) : bus_(bus), speed_(speed) {}
  void play();

  Bus& bus_;
  double speed_;
  std::string name_ = "replay";
  std::vector<Recorded> messages_;
  std::atomic<bool> done_{false}, stop_{false};
  std::atomic<std::uint64_t> published_{0};
  NodeThread thread_{"replay"};
  std::thread player_;
};

}  // namespace plr::kernel
