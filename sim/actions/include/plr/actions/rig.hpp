// The action model on the Simbody simulation with the ARA* lattice planner,
// all in this process: the shipped robot and lattice loaded once, a trailer
// put in front of the robot as often as wanted. What offline work (the
// chooser's training rollouts, the evaluation) runs actions on; a process
// forked from a rig inherits the loaded robot and planner.
#pragma once

#include <plr/expected.hpp>

#include <cstdint>
#include <memory>
#include <vector>

#include "plr/actions/action_model.hpp"
#include "plr/actions/in_process.hpp"
#include "plr/actions/unloader_simulation.hpp"
#include "plr/planning/lattice_planner.hpp"
#include "plr/sim/robot_model.hpp"
#include "plr/sim/world.hpp"

namespace plr::actions {

// Offline work (generation, chooser training, evaluation) bounds its plans by
// expansions, so results do not depend on the machine's load; this time
// limit is only a safety net against a stuck search.
inline constexpr double kOfflinePlanTimeoutS = 1800.0;

class Rig {
 public:
  static plr::Expected<std::unique_ptr<Rig>> create(ActionOptions options);

  // A new simulation of `truth` (with masses), the robot at home, at the
  // rig's fidelity.
  void reset(const sim::World& truth);
  // The fidelity of this simulation and the next ones reset() makes.
  void set_fidelity(sim::Fidelity fidelity);
  // The simulation's state with what the robot learnt, as the bytes of a
  // TruckState (state_bytes.hpp): to run on from it here or in another
  // process, bit for bit.
  std::vector<std::uint8_t> snapshot(const Memory& memory) const;
  // Puts the simulation in the state `bytes` hold (untrusted: verified) and
  // returns what the robot had learnt there.
  plr::Expected<Memory> restore(const std::vector<std::uint8_t>& bytes);

  const sim::RobotModel& robot() const { return robot_; }
  const ActionModel& model() const { return model_; }
  UnloaderSimulation& simulation() { return simulation_; }
  const UnloaderSimulation& simulation() const { return simulation_; }
  InProcessBackend& backend() { return backend_; }

 private:
  Rig(sim::RobotModel robot, planning::LatticeConfig lattice, ActionOptions options);

  sim::RobotModel robot_;
  planning::LatticePlanner planner_;
  ActionModel model_;
  sim::Fidelity fidelity_ = sim::Fidelity::kFull;
  UnloaderSimulation simulation_;  // assigned anew by reset(): the backend keeps its address
  InProcessBackend backend_;
};

}  // namespace plr::actions
