#include "segment_config.hpp"

#include "slot_size.hpp"

#include <algorithm>

namespace plr::kernel {

shm::TopicConfig topic_segment_config(const TopicSettings& t, std::uint64_t type_id) {
  shm::TopicConfig c;
  c.slot_count = static_cast<std::uint32_t>(std::max<std::size_t>(t.depth, 2));
  c.slot_size = static_cast<std::uint32_t>(slot_size(t, {type_id}));
  c.policy = t.policy == TopicPolicy::Reliable ? shm::Policy::kReliable : shm::Policy::kKeepLast;
  c.wait_mode = t.busy_poll ? shm::WaitMode::kPolling : shm::WaitMode::kBlocking;
  c.spin_us = t.spin_us;
  return c;
}

shm::ServiceConfig service_segment_config(const TopicSettings& s, std::uint64_t request_type,
                                          std::uint64_t reply_type, std::size_t hosts) {
  const std::size_t others = hosts > 1 ? hosts - 1 : 1;
  return {.slot_count = 4,
          .slot_size = static_cast<std::uint32_t>(slot_size(s, {request_type, reply_type})),
          .max_clients = static_cast<std::uint32_t>(std::min<std::size_t>(2 * others, 64)),
          .wait_mode = shm::WaitMode::kBlocking};
}

}  // namespace plr::kernel
