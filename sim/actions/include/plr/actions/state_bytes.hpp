// A state of the action model's world — the simulation's checkpoint and
// what the robot learnt about the boxes (Memory) — as plr.msg.TruckState
// (sdk/schemas/generator.fbs), to hand to another process and back. The
// physics bytes carry every double exactly, so a state restored from them
// continues bit for bit as the original would (same binary and machine).
#pragma once

#include <plr/msg/generator_generated.h>
#include <plr/expected.hpp>

#include <memory>
#include <string>

#include "plr/actions/action_model.hpp"
#include "plr/actions/unloader_simulation.hpp"

namespace plr::actions {

struct SimState {
  std::shared_ptr<const UnloaderSimulation::Saved> saved;
  Memory memory;
};

flatbuffers::Offset<plr::msg::ActionMemory> build(flatbuffers::FlatBufferBuilder& fbb,
                                                  const Memory& memory);
flatbuffers::Offset<plr::msg::TruckState> build(flatbuffers::FlatBufferBuilder& fbb,
                                                const SimState& state);

// Untrusted input (verified bytes, unchecked values): counts and strings are
// bounded, the physics bytes checked (Snapshot::from_bytes). The error is
// one line, "<origin>: <field>: <cause>".
plr::Expected<Memory> from_message(const plr::msg::ActionMemory& memory, const std::string& origin);
plr::Expected<SimState> from_message(const plr::msg::TruckState& state, const std::string& origin);

}  // namespace plr::actions
