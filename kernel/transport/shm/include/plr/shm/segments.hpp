// Names and clean-up of the shared-memory segments of a pipeline run.
//
// Segments are /dev/shm/plr.<uid>.<run_id>.<t|s><hash>, mode 0600, each stamped
// with its owner's pid and start time. The owner removes its segment on clean
// exit; after a crash the supervisor calls these.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

#include "plr/shm/types.hpp"

namespace plr::shm {

// run_id: 1..48 characters of [A-Za-z0-9_-].
bool valid_run_id(std::string_view run_id) noexcept;
// Topic and service names: 1..127 bytes, no NUL.
bool valid_endpoint_name(std::string_view name) noexcept;

// "/plr.<uid>.<run_id>.t<16 hex of FNV-1a(topic)>" (the name given to shm_open).
std::string topic_segment_name(std::string_view run_id, std::string_view topic);
std::string service_segment_name(std::string_view run_id, std::string_view service);

// Unlinks every segment of this user's run, whoever owns it (call once every
// process of the run has stopped). Returns how many were removed.
Result<std::size_t> remove_run_segments(std::string_view run_id) noexcept;

// Unlinks this user's plr segments whose stamped owner (pid + start time) is
// dead, and half-created ones older than a few seconds. Safe while other runs
// are live. Returns how many were removed.
std::size_t reclaim_stale_segments() noexcept;

}  // namespace plr::shm
