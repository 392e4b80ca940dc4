// The shared-memory geometry of a pipeline's topic or service: what the
// bridge creates, and what `plr validate` and `plr run` count before a run.
#pragma once

#include "pipeline_config.hpp"

#include <plr/shm/service.hpp>
#include <plr/shm/types.hpp>

#include <cstddef>
#include <cstdint>

namespace plr::kernel {

// Slots from the topic's settings (depth, policy, waiting), each as large as
// the config's slot_size or else the bound of the topic's message type.
shm::TopicConfig topic_segment_config(const TopicSettings& settings, std::uint64_t type_id);

// Slots for the larger of request and reply (or the config's slot_size), and
// two client channels per other host of the run (`hosts` counts them all):
// one for a restarted host while its dead predecessor's is being reclaimed.
shm::ServiceConfig service_segment_config(const TopicSettings& settings, std::uint64_t request_type,
                                          std::uint64_t reply_type, std::size_t hosts);

}  // namespace plr::kernel
