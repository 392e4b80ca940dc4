// What the action model needs from the world it acts in: look, plan, move.
// Two implementations: in-process (plr/actions/in_process.hpp: the Simbody
// simulation and a planner called directly, for offline work) and over the
// bus (the strategy executor plug-in: the simulator or the robot driver and
// the `plan` service).
//
// A backend's errors end the action: PLR_ERR_UNAVAILABLE or PLR_ERR_TIMEOUT
// when the world went away (a simulator host died), PLR_ERR_CANCELLED when
// the caller is stopping.
#pragma once

#include <plr/expected.hpp>

#include <cstdint>
#include <vector>

#include "plr/actions/unloader_simulation.hpp"
#include "plr/planning/plan_messages.hpp"
#include "plr/sim/world.hpp"

namespace plr::actions {

// What the robot perceives: boxes without masses, its own joints, what the
// plate holds, and how many boxes have left the trailer so far.
struct Perceived {
  sim::World world;
  sim::JointVector q = sim::JointVector::Zero();
  std::vector<std::uint32_t> held;
  std::uint32_t unloaded = 0;
  double sim_time_s = 0.0;
};

class Backend {
 public:
  virtual ~Backend() = default;
  virtual plr::Expected<Perceived> observe() = 0;
  // Plans on `world` (the query's held and ignored boxes apply to it).
  virtual plr::Expected<planning::DecodedPlanResponse> plan(const planning::PlanQuery& query,
                                                            const sim::World& world) = 0;
  // A motion the robot refused (it does not start where the robot is) is
  // an error with PLR_ERR_STATE; the action goes on without it.
  virtual plr::Expected<Executed> execute(const Motion& motion) = 0;
};

}  // namespace plr::actions
