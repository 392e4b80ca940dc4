// How many bytes one message of a topic or service may take on a transport:
// what its shared-memory slots are sized for, and the most DDS accepts.
#pragma once

#include "pipeline_config.hpp"

#include <cstddef>
#include <cstdint>
#include <initializer_list>

namespace plr::kernel {

// For a message type without a declared bound (or unknown to the SDK).
inline constexpr std::size_t kDefaultSlotSize = std::size_t{1} << 20;

// The type's declared bound (the `max_bytes` attribute of its schema), else
// kDefaultSlotSize.
std::size_t message_bound(std::uint64_t type_id);

// The config's slot_size when set, else the largest bound of `type_ids` (a
// topic's message; a service's request and reply).
std::size_t slot_size(const TopicSettings& settings, std::initializer_list<std::uint64_t> type_ids);

}  // namespace plr::kernel
