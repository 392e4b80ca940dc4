// A strategy run open loop in process, as the executor runs it: observe,
// follow the tree's edge for the observation, run the action; where the tree
// ends (or after an action that moved nothing, as RunRules has it), strategy
// H's ranking takes over. Without a strategy it is H alone. For comparing a
// library strategy with H from one state: the generator over its horizon on
// held-out mass particles, the chooser's training from each visited state.
#pragma once

#include <plr/expected.hpp>

#include <cstdint>
#include <optional>

#include "plr/actions/action_model.hpp"
#include "plr/sim/hardcoded_strategy.hpp"
#include "plr/sim/strategy.hpp"

namespace plr::actions {

struct OpenLoopRun {
  std::uint64_t actions = 0;
  std::uint64_t strategy_steps = 0;  // actions the strategy chose (the rest: H)
  std::uint32_t boxes = 0;
  double robot_time_s = 0.0;
};

// `memory` is the state's: what the robot learnt before it, and after.
plr::Expected<OpenLoopRun> run_open_loop(const ActionModel& model, Backend& backend, Memory& memory,
                                         const std::optional<sim::Strategy>& strategy,
                                         const sim::HardcodedParams& h, std::uint64_t max_actions);

}  // namespace plr::actions
