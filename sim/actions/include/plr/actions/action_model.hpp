// The action model: one abstract action (Pick(height, side), Sweep(height))
// instantiated on the world as the robot perceives it, turned into planning
// queries and motions, and run through a backend (backend.hpp); the outcome
// says what it achieved and what it cost.
//
//   plr::actions::ActionModel model(robot, options);
//   plr::actions::Memory memory;                 // belongs to the world state
//   auto outcome = model.run(plr::sim::make_sweep(plr::sim::Height::kLow), backend, memory);
//
// Robot time is deterministic: the trajectories' durations and settle times
// plus a planning-time model of each query's expansions (PlanTimeModel), not
// the planner's wall time, which is reported beside it.
#pragma once

#include <plr/expected.hpp>

#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "plr/actions/backend.hpp"
#include "plr/actions/instantiate.hpp"
#include "plr/planning/plan_query.hpp"
#include "plr/sim/observation.hpp"
#include "plr/sim/strategy.hpp"

namespace plr::actions {

// Planning time the robot waits for, as a function of the search's work
// rather than of the machine's load: per_query + per_expansion * expansions,
// per mode (index = plan mode 1..6; fitted to the ARA* planner's measured
// times on A1 and B1, docs/executor.md).
struct PlanTimeModel {
  std::array<double, 7> per_query_s{0.0, 0.001, 0.005, 0.0005, 0.001, 0.0005, 0.002};
  std::array<double, 7> per_expansion_s{0.0, 0.001, 0.0043, 0.0005, 0.0004, 0.0002, 0.001};
  double seconds(planning::PlanMode mode, std::uint64_t expansions) const;
};

struct ActionOptions {
  sim::ObservationParams observation;
  Geometry geometry;
  PlanTimeModel plan_time;
  // Planning: a budget of search expansions, not of time, makes each plan
  // (and so each outcome) the same whatever the machine's load. The time
  // limit is a safety net far above what the budget takes (5000 M2
  // expansions that find nothing take ~20 s on the 2-core machine); a search
  // it ends fails the action (PLR_ERR_INVALID) instead of letting the load
  // decide the outcome. ARA* spends a whole budget lowering ε, so by default
  // it stops at its first solution (ε = 5).
  double plan_timeout_s = 120.0;
  std::uint64_t plan_expansions = 5000;
  std::vector<double> plan_epsilons{5.0};
  // Pick candidates tried per action, and different grips tried per box
  // (more cups, slower carries) before it is left to a sweep or in the trailer.
  std::size_t pick_candidates = 4;
  int grip_attempts = 3;
  double settle_s = 0.3;  // after a grip or a release
  std::array<double, 3> nose_home{0.5, 0.0, 0.0};
  std::array<double, 3> nose_down{0.0, 0.05, 0.0};
  std::array<double, 3> nose_sweep{0.0, 0.05, 0.3};
  // Raised, its tip up: what lies on the scoop or beside the belt slides
  // onto the belt, which carries it off.
  std::array<double, 3> nose_shake{0.3, -0.5, 0.0};
  // Arm folded over the base: out of the way of boxes leaving on the belt.
  std::array<double, 4> arm_clear{0.0, -1.0, 2.0, 0.0};
  double retreat_m = 0.3;          // base backs off after an action that ends stowed
  double dropoff_backoff_m = 0.5;  // base backs off before swinging a load to the nose
  double carry_height_m = 1.4;     // plate height a load is lowered to before the drop-off
  // What finding an action not applicable costs: looking and deciding.
  double not_applicable_s = 0.5;
  // Planning while moving: while a step's motion runs, the step known to
  // follow it is planned (on another thread) from the motion's predicted
  // end state, and its plan is used only if the state observed afterwards
  // is the predicted one (PlanAhead); the robot then waits only for the
  // modelled planning the motion did not cover.
  bool plan_while_moving = true;

  // Whether the values are consistent; the error names the parameter.
  plr::Status check() const;
};

// A box whose grip failed, and what the next attempt changes.
struct GripHistory {
  int failures = 0;
  int drops = 0;  // held, then lost while carried: the load, not the weight alone
  int cups = 0;   // cups the last failed grasp pose covered
  bool given_up = false;
  std::string last, why;  // the last failure; why no more attempts are made
  // The boxes around it when it was given up: once one of them has left the
  // trailer, what held it back may be gone (A2 seed 2: a retract into a
  // neighbour since unloaded), and it is tried afresh.
  std::set<std::uint32_t> neighbours;
};

// What the robot has learnt about this trailer's boxes, kept with the world
// state (not in a node) so that a run, a simulation particle and a restored
// checkpoint all carry it.
struct Memory {
  std::map<std::uint32_t, GripHistory> grips;
  std::set<std::uint32_t> ungripped;  // grasps that failed since the last unloaded box
  // Why the last pick of a box stopped before its grasp, since the last
  // unloaded box: it is not tried again until another box has left.
  std::map<std::uint32_t, std::string> unreached;
  // Boxes lying on the robot that it tried to shake off: not tried again.
  std::set<std::uint32_t> shaken;
};

// When a state observed after a motion is the one predicted before it: the
// joints within what the robot accepts as a trajectory's start (a plan
// from the predicted state must start where the robot is), the same boxes
// held, and every box within kBoxShift (m) and kBoxTurn (rad) of its
// predicted pose (the simulator's own "moved", Executed::moved): a box that
// fell or was pushed makes it another world, planned for afresh.
struct PlanAhead {
  static constexpr double kJoints = 1e-4;  // rad or m, any joint
  static constexpr double kBoxShift = 0.01;
  static constexpr double kBoxTurn = 0.02;
  static bool same_state(const Perceived& predicted, const Perceived& observed);
};

// One planning query of an action, for the planner statistics.
struct QueryRecord {
  planning::PlanMode mode = planning::PlanMode::kArm;
  bool answered = false;  // false: the planner never answered (lost, timed out)
  planning::PlanStatus status = planning::PlanStatus::kSolved;
  std::string planner;
  std::uint64_t expansions = 0;
  double planning_ms = 0.0;  // as the planner measured it
  bool escaped = false;      // it ran the M6 escape first
  double escape_ms = 0.0;
  bool planned_ahead = false;  // made while the motion before it ran, and used
};

struct Outcome {
  // Not applicable: nothing in the action's region could be instantiated
  // (no box of that height and side to pick, no pile to sweep); the robot
  // did not move and only not_applicable_s passed. `why` says what was missing.
  bool applicable = true;
  std::string why;
  std::uint32_t boxes = 0;  // boxes that left the trailer
  // Boxes still in the trailer that it moved more than 5 cm or turned more
  // than 0.2 rad: an action that unloaded nothing may still have changed
  // what the others can do.
  std::uint32_t shifted = 0;
  // When each left, in robot seconds after the action's start.
  std::vector<double> unloaded_at_s;
  double robot_time_s = 0.0;  // exec_s + plan_model_s
  double exec_s = 0.0;        // trajectories and settling
  double plan_model_s = 0.0;  // planning the robot waited for (PlanTimeModel)
  double plan_wall_s = 0.0;   // what planning took on this machine
  // Plans made while moving (ActionOptions::plan_while_moving): asked for,
  // used (the observed state was the predicted one), and the modelled
  // planning of the used ones that their motions covered (not charged).
  std::uint32_t plans_ahead = 0;
  std::uint32_t plans_ahead_used = 0;
  double plan_hidden_s = 0.0;
  std::uint32_t robot_trailer_contacts = 0;
  bool failed_grasp = false;  // a grasp held nothing or its load dropped
  std::uint32_t drops = 0;    // loads lost while carried
  double sim_time_s = 0.0;    // the world's clock afterwards (0 if unknown)
  std::vector<QueryRecord> queries;
};

// Boxes of `before` still in `after` that moved more than 5 cm or turned
// more than 0.2 rad (Outcome::shifted).
std::uint32_t boxes_shifted(const sim::World& before, const sim::World& after);

// What an action tells its caller while it runs: each step as it starts
// ("approach", "drop-off"), for a live display, and what is worth a log line
// (a grasp that failed, a box given up).
struct Reporter {
  std::function<void(const std::string& step)> progress;
  std::function<void(const std::string& line)> note;
};

class ActionModel {
 public:
  // The robot model must outlive the action model.
  ActionModel(const sim::RobotModel& robot, ActionOptions options);

  // Runs `action` from the backend's current state. Backend errors that end
  // the action (the world went away, the caller stops) are returned; what
  // the action did until then is lost with them.
  plr::Expected<Outcome> run(sim::Action action, Backend& backend, Memory& memory,
                             const Reporter& reporter = {}) const;

  // What stands in front of the robot, as the strategy sees it: the boxes
  // lying on the robot are not part of it (an action shakes them off
  // first), unless nothing else is left or a shake left them there.
  sim::SceneAnalysis scene(const Perceived& w, const Memory& memory) const;

  const ActionOptions& options() const { return options_; }
  const sim::RobotModel& robot() const { return *robot_; }

 private:
  const sim::RobotModel* robot_;
  ActionOptions options_;
};

}  // namespace plr::actions
