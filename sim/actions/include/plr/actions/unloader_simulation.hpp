// The trailer with the robot in it, simulated: the box physics (Simbody,
// plr/sim/physics.hpp) with the robot's links, suction plate and conveyor
// moved along timed trajectories. What the simulator plug-in serves over the
// bus and what the in-process action model runs on, one implementation.
#pragma once

#include <plr/expected.hpp>

#include <cstdint>
#include <functional>
#include <memory>
#include <utility>
#include <vector>

#include "plr/planning/plan_messages.hpp"
#include "plr/sim/physics.hpp"
#include "plr/sim/robot_model.hpp"

namespace plr::actions {

enum class Suction { kKeep, kOn, kOff };

// One move of the robot: a trajectory (times from 0), what the suction does
// before and after it, whether the conveyor runs, and how long to let what
// moved come to rest afterwards.
struct Motion {
  std::vector<planning::TimedPoint> points;
  Suction before = Suction::kKeep;
  Suction after = Suction::kKeep;
  // The plate's cup valves for a kOn (Simulation::suction_on): cups that
  // would seal on boxes not to be taken stay closed. Empty: all open.
  std::vector<bool> cups_open;
  bool conveyor = true;
  double settle_s = 0.0;
};

struct Executed {
  std::vector<std::uint32_t> unloaded;   // boxes that left the trailer
  std::vector<double> unloaded_after_s;  // when, in s after the motion's start
  std::vector<std::uint32_t> held;       // what the plate holds at the end
  std::vector<std::uint32_t> moved;      // boxes displaced by more than 1 cm
  std::uint32_t robot_trailer_contacts = 0;
  std::vector<sim::SuctionEvent> suction;  // grips refused and loads dropped
  double sim_time_s = 0.0;                 // the simulated clock afterwards
  // The base stalled: the boxes pushed back on the robot harder than its
  // drive can push (UnloaderOptions::base_max_push_force) while the base
  // moved, so the robot stopped there and left the rest of the trajectory.
  bool stalled = false;
  double stall_force = 0.0;    // N the boxes pushed back with when it stalled
  double stall_after_s = 0.0;  // s after the motion's start
  // The largest push back against the base's motion over the motion, N
  // (filtered as the stall check sees it; 0 if the base did not move).
  double peak_push_force = 0.0;
};

struct UnloaderOptions {
  double control_period_s = 0.01;  // the robot's pose is updated this often
  double belt_speed = 0.8;         // m/s of the nose conveyor
  double carry_max_s = 4.0;        // the belt keeps running this long at most after a motion
  // The base's drive: the force its wheels can push with along the
  // trailer's axis. When what the boxes push back on the robot (the sum of
  // robot_contact_forces() against the base's motion, averaged over
  // base_push_filter_s so that the blow of meeting a box is not a stall)
  // exceeds it while the base moves, the base stalls. Default: four
  // omnidirectional wheel drives of about 0.5 kN tractive force each at
  // sweep speed (a 2 kW drive train at 1 m/s).
  double base_max_push_force = 2000.0;  // N
  double base_push_filter_s = 0.1;
  sim::PhysicsOptions physics;
  // How accurately the boxes are simulated (plr/sim/fidelity.hpp): a
  // setting of the run, kept across restore().
  sim::Fidelity fidelity = sim::Fidelity::kFull;
};

// Where the robot starts (plr/sim/robot_model.hpp).
using sim::home_configuration;

class UnloaderSimulation {
 public:
  // `truth` with masses (W^t). The robot model must outlive the simulation.
  UnloaderSimulation(const sim::RobotModel& robot, const sim::World& truth,
                     const sim::JointVector& q = home_configuration(),
                     const UnloaderOptions& options = {});
  ~UnloaderSimulation();
  UnloaderSimulation(UnloaderSimulation&&) noexcept;
  UnloaderSimulation& operator=(UnloaderSimulation&&) noexcept;

  // Called after every control period of a motion with the robot's
  // configuration then (q() is the motion's end only once it returns): what
  // a live view of the motion draws.
  using PeriodObserver = std::function<void(const sim::JointVector& q)>;

  // Runs a motion. Refused (with the reason) when its first point is not
  // where the robot is, or its times decrease: a controller would refuse it.
  plr::Expected<Executed> execute(const Motion& motion, const PeriodObserver& observer = {});

  const sim::RobotModel& robot() const;
  sim::World truth() const;      // boxes still in the trailer, with masses
  sim::World perceived() const;  // the same without masses (W)
  const sim::JointVector& q() const;
  std::vector<std::uint32_t> held() const;
  std::uint32_t boxes_unloaded() const;
  double time() const;
  const sim::Simulation& physics() const;
  void set_fidelity(sim::Fidelity fidelity);

  // In-memory checkpoints; a restored simulation repeats bit for bit.
  struct Saved;
  std::shared_ptr<const Saved> save() const;
  void restore(const Saved& saved);
  // A checkpoint's parts, to carry it to another process (state_bytes.hpp):
  // the physics, the robot's joints, the boxes unloaded so far.
  static const sim::Snapshot& physics_of(const Saved& saved);
  static const sim::JointVector& q_of(const Saved& saved);
  static std::uint32_t unloaded_of(const Saved& saved);
  static std::shared_ptr<const Saved> make_saved(sim::Snapshot physics, const sim::JointVector& q,
                                                 std::uint32_t unloaded);

  // Gives the boxes named by id these masses (kg) and leaves everything else
  // as it is: the same state on another particle of the belief over W^t
  // (sim::sample_masses). An unknown id or a mass that is not finite and > 0
  // is refused, naming it, and changes nothing.
  plr::Status set_masses(const std::vector<std::pair<std::uint32_t, double>>& masses);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace plr::actions
