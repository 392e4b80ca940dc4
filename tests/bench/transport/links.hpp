// One benchmark "link": a data direction (sender -> receiver) plus an ack
// direction back, over one transport. Each process sets up its own side after
// fork.
#pragma once

#include <cstddef>
#include <cstdint>
#include <ctime>
#include <string>

namespace plr::bench {

inline std::uint64_t now_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::uint64_t>(ts.tv_sec) * 1'000'000'000ULL +
         static_cast<std::uint64_t>(ts.tv_nsec);
}

class Link {
 public:
  virtual ~Link() = default;
  // Sender side.
  virtual bool send(std::size_t size, std::uint64_t stamp, std::uint64_t seq) = 0;
  virtual bool wait_ack(std::uint64_t& seq) = 0;
  // Receiver side: stamp is what the sender stamped just before send().
  virtual bool receive(std::uint64_t& stamp, std::uint64_t& seq) = 0;
  virtual bool ack(std::uint64_t seq) = 0;
};

// Cyclone DDS (C API) over loopback; CYCLONEDDS_URI must be set.
// Setup is split so that both processes create entities, then wait for matching.
Link* make_dds_link(bool sender, std::size_t max_size, std::string& error);

}  // namespace plr::bench
