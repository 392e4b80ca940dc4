// Motion-planning queries and results: what a caller asks any planner
// (plr/planning/planner.hpp) and what it answers, in-process or over the
// `plan` service (sdk/schemas/plan.fbs, plr/planning/plan_messages.hpp).
#pragma once

#include <plr/expected.hpp>

#include <cstdint>
#include <string>
#include <variant>
#include <vector>

#include "plr/sim/collision.hpp"
#include "plr/sim/robot_model.hpp"
#include "plr/sim/trajectory.hpp"
#include "plr/sim/world.hpp"

namespace plr::planning {

using sim::JointVector;
using sim::PlateTarget;

// The planner modes of the paper's Table I.
enum class PlanMode : int {
  kArm = 1,           // M1: the 4 arm joints
  kArmBase = 2,       // M2: base_x + the 4 arm joints
  kNose = 3,          // M3: the 3 nose joints
  kArmCartesian = 4,  // M4: plate along a straight line (1 DOF: progress)
  kBaseLine = 5,      // M5: base_x alone, straight along the trailer axis
  kEscape = 6,        // M6: Dijkstra to the nearest collision-free state
};

// "M1 arm", ... ; "unknown" for values outside the enum.
const char* to_string(PlanMode mode);

// Joints a mode plans (configuration indices). M4 moves the arm joints but
// plans one progress variable; M6 alone plans base and arm (+ nose lift).
std::vector<int> planned_joints(PlanMode mode);

// Reach these values of the mode's planned joints (others are ignored and
// stay at their start values).
struct JointGoal {
  JointVector q = JointVector::Zero();
  double tolerance = 1e-3;  // per joint, rad or m
};

// Put the plate at a position with a yaw (see PlateTarget).
struct PoseGoal {
  PlateTarget target;
  double position_tolerance = 0.005;  // m
  double yaw_tolerance = 0.01;        // rad
};

struct PlanQuery {
  PlanMode mode = PlanMode::kArm;
  JointVector start = JointVector::Zero();
  // M3 and M5 take joint goals, M4 pose goals, M1 and M2 either; M6 none.
  std::variant<std::monostate, JointGoal, PoseGoal> goal;

  double time_limit_s = 5.0;  // for the whole query, escape included
  // After the first solution, keep improving (ARA*: lower ε; OMPL:
  // shortcutting) for at most this long, within time_limit_s.
  double improve_time_s = 0.1;
  double eps_initial = 5.0;
  double eps_final = 1.0;
  double eps_decrement = 2.0;
  // Deterministic planning: stop after this many search expansions in total
  // (escape included; RRTConnect: iterations) with the best solution found
  // by then. improve_time_s is then ignored, so the answer does not depend on
  // the machine's load; time_limit_s stays a safety net. 0 = no budget.
  std::uint64_t max_expansions = 0;

  // Start in collision: run M6 first and plan from where it ends.
  bool escape_if_start_invalid = true;
  // Boxes held by the plate at `start` (world poses); they move with the arm.
  std::vector<sim::Box> held_boxes;
  // World boxes not to collide with (e.g. the one the plate approaches).
  std::vector<std::uint32_t> ignored_boxes;
};

enum class PlanStatus {
  kSolved,
  kTimeout,         // no solution within time_limit_s
  kStartInvalid,    // start in collision (and no escape) or beyond limits
  kGoalInvalid,     // goal in collision, beyond limits or out of reach
  kNoPath,          // the search space was exhausted
  kInvalidRequest,  // malformed query; message says what
};

const char* to_string(PlanStatus status);

struct PlanStats {
  std::size_t expansions = 0;
  double first_solution_s = 0.0;  // wall time; includes the escape, if any
  // The same on this thread's CPU clock: what the query costs regardless of
  // other load on the machine.
  double first_solution_cpu_s = 0.0;
  double planning_time_s = 0.0;  // total wall time of the query
  double final_eps = 0.0;
  double suboptimality_bound = 0.0;
  double cost = 0.0;                   // the search's cost: estimated execution time (s)
  std::uint64_t collision_checks = 0;  // states + sweeps
  bool escaped = false;                // M6 ran first
  bool budget_exhausted = false;       // max_expansions ended the search
  bool time_limit_hit = false;         // time_limit_s ended it: the result depends on load
  double escape_time_s = 0.0;
  double escape_cpu_s = 0.0;
  // Expansions that joined or followed a path of an earlier query (the
  // lattice planner's experience graph; 0 without experience).
  std::size_t experience_edges = 0;
};

struct PlanResult {
  PlanStatus status = PlanStatus::kNoPath;
  std::string message;            // why, when not solved
  std::vector<JointVector> path;  // waypoints, start .. goal (full configurations)
  sim::Trajectory trajectory;     // path timed within velocity/acceleration limits
  PlanStats stats;
};

// Whether the query is well formed for this robot; the error says what is
// wrong (e.g. "M3 nose needs a joint goal"). Checks types, finite values,
// limits and time budgets; not collisions.
plr::Status check_query(const PlanQuery& query, const sim::RobotModel& robot);

// Applies a query's held and ignored boxes to a checker for the lifetime of
// the scope, then removes them again.
class QueryScope {
 public:
  QueryScope(sim::CollisionChecker& checker, const PlanQuery& query);
  ~QueryScope();
  QueryScope(const QueryScope&) = delete;
  QueryScope& operator=(const QueryScope&) = delete;

 private:
  sim::CollisionChecker& checker_;
};

}  // namespace plr::planning
