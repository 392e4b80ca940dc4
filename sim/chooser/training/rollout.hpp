// Rollouts from one state of the trailer: the nearest library strategy and
// strategy H, each for a few actions from the same snapshot, side by side
// as jobs of kind chooser.rollout (plr/jobs), each in a child process
// forked from the rig's: it inherits the loaded robot and planner, restores
// the state bit for bit and runs its own simulation.
#pragma once

#include <plr/expected.hpp>

#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

#include "plr/actions/rig.hpp"
#include "plr/sim/hardcoded_strategy.hpp"
#include "plr/sim/strategy.hpp"

namespace plr::chooser {

struct Rollout {
  std::uint64_t actions = 0;
  std::uint32_t boxes = 0;
  double robot_time_s = 0.0;
  std::vector<std::uint8_t> end;  // the TruckState it ended in

  // Boxes per robot second (0 when nothing moved).
  double rate() const { return robot_time_s > 0 ? boxes / robot_time_s : 0.0; }
};

// `strategy` (nullopt: H alone) from a state, its boxes given `masses`
// (id, kg) first (a particle; empty: the state's own).
struct RolloutJob {
  std::optional<sim::Strategy> strategy;
  std::vector<std::pair<std::uint32_t, double>> masses;
};

// One rollout on `rig`, from `state`, at most `max_actions` actions.
plr::Expected<Rollout> rollout(actions::Rig& rig, const std::vector<std::uint8_t>& state,
                               const RolloutJob& job, const sim::HardcodedParams& h,
                               std::uint64_t max_actions);

// Each job in a child process, at most `workers` at once; results in the
// jobs' order. A child that dies is an error naming its signal.
std::vector<plr::Expected<Rollout>> rollouts(actions::Rig& rig,
                                             const std::vector<std::uint8_t>& state,
                                             const std::vector<RolloutJob>& todo,
                                             const sim::HardcodedParams& h,
                                             std::uint64_t max_actions, int workers);

}  // namespace plr::chooser
