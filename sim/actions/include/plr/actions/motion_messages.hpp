// Motions and their outcomes as bus messages (sdk/schemas/simulation.fbs):
// ExecuteRequest <-> Motion, ExecuteOutcome <-> Executed. The executor's bus
// backend and the simulator plug-in speak through these.
#pragma once

#include <plr/expected.hpp>

#include "plr/actions/unloader_simulation.hpp"

namespace plr::msg {
struct ExecuteRequest;
struct ExecuteOutcome;
}  // namespace plr::msg
namespace flatbuffers {
class FlatBufferBuilder;
}

namespace plr::actions {

void encode_execute_request(const Motion& motion, flatbuffers::FlatBufferBuilder& out);
// Checks every field of a verified message; the error names the bad one.
plr::Expected<Motion> decode_execute_request(const plr::msg::ExecuteRequest& request);

void encode_execute_outcome(const Executed& executed, std::uint32_t boxes_remaining,
                            flatbuffers::FlatBufferBuilder& out);
// A refused motion (ok = false) comes back as an error with its message.
plr::Expected<Executed> decode_execute_outcome(const plr::msg::ExecuteOutcome& outcome);

}  // namespace plr::actions
