// Rollouts from one state of the trailer: the nearest library strategy and
// strategy H, each for a few actions from the same snapshot, side by side
// in child processes (fork: each child inherits the loaded robot and
// planner, restores the state bit for bit and runs its own simulation).
#pragma once

#include <plr/expected.hpp>

#include <cstdint>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "plr/actions/action_model.hpp"
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

// The action model on the Simbody simulation with the ARA* lattice planner
// (actions::Rig), with snapshots of its state and rollouts from them.
class Rig {
 public:
  static plr::Expected<std::unique_ptr<Rig>> create(const sim::ObservationParams& observation);

  // A TruckState of `truth` at rest, the robot at home, nothing learnt.
  std::vector<std::uint8_t> start(const sim::World& truth);
  // What the robot perceives in `state`.
  plr::Expected<actions::Perceived> observe(const std::vector<std::uint8_t>& state);

  // A rollout: `strategy` (nullopt: H alone) from the state, its boxes
  // given `masses` (id, kg) first (a particle; empty: the state's own).
  struct Job {
    std::optional<sim::Strategy> strategy;
    std::vector<std::pair<std::uint32_t, double>> masses;
  };
  // From `state`, at most `max_actions` actions.
  plr::Expected<Rollout> run(const std::vector<std::uint8_t>& state, const Job& job,
                             const sim::HardcodedParams& h, std::uint64_t max_actions);

  // Each job in a child process, at most `workers` at once; results in
  // the jobs' order. A child that dies is an error naming its signal.
  std::vector<plr::Expected<Rollout>> run_parallel(const std::vector<std::uint8_t>& state,
                                                   const std::vector<Job>& jobs,
                                                   const sim::HardcodedParams& h,
                                                   std::uint64_t max_actions, int workers);

 private:
  explicit Rig(std::unique_ptr<actions::Rig> rig) : rig_(std::move(rig)) {}
  plr::Expected<actions::Memory> restore(const std::vector<std::uint8_t>& state);
  std::vector<std::uint8_t> snapshot(const actions::Memory& memory) const;

  std::unique_ptr<actions::Rig> rig_;
};

}  // namespace plr::chooser
