#include "arastar_planner.hpp"

#include <algorithm>
#include <chrono>

#include "lattice/robot_lattice.hpp"
#include "plr/sim/trajectory.hpp"

namespace plr::arastar {

using sim::JointVector;
using sim::PlanMode;
using sim::PlanResult;
using sim::PlanStatus;

namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

PlanResult fail(PlanStatus status, std::string message) {
  PlanResult r;
  r.status = status;
  r.message = std::move(message);
  return r;
}

std::string budget_message(std::uint64_t budget) {
  return "no solution within the expansion budget of " + std::to_string(budget);
}

// A pose goal is met by many configurations: each IK branch, and with the
// base planned, every base position from which the arm reaches the target.
// The search ends at the first one it meets; the path's last move is
// re-aimed at the one it reaches soonest.
void aim_at_quickest_goal(std::vector<JointVector>& path, const sim::PoseGoal& goal,
                          const ModeLattice& lattice, const sim::CollisionChecker& checker) {
  if (path.size() < 2) return;
  const sim::RobotModel& robot = checker.robot();
  const JointVector from = path[path.size() - 2];
  // How long the last move takes, timed as the trajectory will time it.
  auto time = [&](const JointVector& q) {
    return sim::segment_duration(from, q, robot.all_limits());
  };
  std::vector<double> bases{path.back()[sim::kBaseX]};
  if (std::find(lattice.joints.begin(), lattice.joints.end(), sim::kBaseX) !=
      lattice.joints.end()) {
    const sim::JointLimits& lb = robot.limits(sim::kBaseX);
    const double b0 = from[sim::kBaseX], b1 = path.back()[sim::kBaseX];
    for (double f : {0.0, 0.25, 0.5, 0.75}) bases.push_back(b0 + f * (b1 - b0));
    for (double off = 0.25; off <= 1.0; off += 0.25) {
      bases.push_back(b0 + off);
      bases.push_back(b0 - off);
    }
    std::erase_if(bases, [&](double b) { return b < lb.lower || b > lb.upper; });
  }
  JointVector best = path.back();
  double best_time = time(best);
  for (double b : bases) {
    JointVector seed = path.back();
    seed[sim::kBaseX] = b;
    for (const JointVector& q : robot.arm_ik(goal.target, seed)) {
      const double t = time(q);
      if (t < best_time - 1e-9 && checker.is_valid(q) && checker.is_motion_valid(from, q, false)) {
        best = q;
        best_time = t;
      }
    }
  }
  path.back() = best;
}

}  // namespace

Planner::Planner(LatticeConfig config) : config_(std::move(config)) {}

Planner::Escape Planner::escape(const JointVector& start, sim::CollisionChecker& checker,
                                const sim::PlanQuery& query, sim::PlanStats& stats) {
  JointLattice graph(config_.modes.at(PlanMode::kEscape), checker, start, std::monostate{}, true);
  search::ZeroHeuristic zero;
  search::SearchOptions o;
  o.time_limit_s = query.time_limit_s;
  o.max_expansions = query.max_expansions;
  o.first_solution_only = true;
  const auto r = search_.search(graph, zero, graph.start(), o);
  stats.expansions += r.expansions;
  stats.budget_exhausted = r.budget_exhausted;
  stats.time_limit_hit = r.time_limit_hit;
  Escape e;
  if (r.status == search::SearchStatus::kSolved) {
    e.status = PlanStatus::kSolved;
    for (auto id : r.path) e.path.push_back(graph.config(id));
  } else if (r.budget_exhausted) {
    e.status = PlanStatus::kTimeout;
    e.why = "expansion budget of " + std::to_string(query.max_expansions) + " exhausted";
  } else if (r.status == search::SearchStatus::kTimeout) {
    e.status = PlanStatus::kTimeout;
    e.why = "timeout";
  } else {
    e.why = "none";
  }
  return e;
}

PlanResult Planner::plan(const sim::PlanQuery& query, sim::CollisionChecker& checker) {
  const auto t0 = std::chrono::steady_clock::now();
  const double cpu0 = sim::thread_cpu_seconds();
  const sim::RobotModel& robot = checker.robot();
  if (const std::string err = sim::validate_query(query, robot); !err.empty()) {
    return fail(PlanStatus::kInvalidRequest, err);
  }
  const sim::QueryScope scope(checker, query);
  checker.reset_stats();
  PlanResult result;
  auto finish = [&](PlanResult r) {
    r.stats.planning_time_s = seconds_since(t0);
    r.stats.collision_checks = checker.stats().state_checks + checker.stats().sweep_checks;
    return r;
  };

  // Leave a start in collision first (M6), then plan from there.
  std::vector<JointVector> prefix;
  JointVector start = query.start;
  if (!robot.within_limits(start)) {
    return finish(fail(PlanStatus::kStartInvalid, "start: " + checker.describe_collision(start)));
  }
  if (query.mode == PlanMode::kEscape || !checker.is_valid(start)) {
    if (query.mode != PlanMode::kEscape && !query.escape_if_start_invalid) {
      return finish(fail(PlanStatus::kStartInvalid,
                         "start in collision: " + checker.describe_collision(start)));
    }
    const std::string why = checker.describe_collision(start);
    Escape e = escape(start, checker, query, result.stats);
    result.stats.escaped = query.mode != PlanMode::kEscape || !why.empty();
    result.stats.escape_time_s = seconds_since(t0);
    result.stats.escape_cpu_s = sim::thread_cpu_seconds() - cpu0;
    if (e.status != PlanStatus::kSolved) {
      PlanResult r = fail(PlanStatus::kStartInvalid,
                          "start in collision (" + why + ") and no escape found: " + e.why);
      r.stats = result.stats;
      return finish(r);
    }
    prefix = e.path;
    start = prefix.back();
    if (query.mode == PlanMode::kEscape) {
      result.status = PlanStatus::kSolved;
      result.path = prefix;
      result.stats.first_solution_s = seconds_since(t0);
      result.stats.first_solution_cpu_s = sim::thread_cpu_seconds() - cpu0;
      result.trajectory = sim::Trajectory::from_waypoints(result.path, robot.all_limits());
      return finish(result);
    }
    prefix.pop_back();  // the query's path starts with this state
  }

  const ModeLattice& lattice = config_.modes.at(query.mode);
  // Goals that can be judged before searching.
  if (const auto* jg = std::get_if<sim::JointGoal>(&query.goal)) {
    JointVector g = start;
    for (int j : lattice.joints) g[j] = jg->q[j];
    if (!checker.is_valid(g))
      return finish(fail(PlanStatus::kGoalInvalid, "goal: " + checker.describe_collision(g)));
  } else if (const auto* pg = std::get_if<sim::PoseGoal>(&query.goal);
             pg && query.mode != PlanMode::kArmBase) {
    const auto sols = robot.arm_ik(pg->target, start);
    if (sols.empty())
      return finish(fail(PlanStatus::kGoalInvalid, "goal: no arm IK solution within joint limits"));
    bool any = false;
    for (const JointVector& q : sols) any = any || checker.is_valid(q);
    if (!any) {
      return finish(fail(
          PlanStatus::kGoalInvalid,
          "goal: every IK solution collides (" + checker.describe_collision(sols.front()) + ")"));
    }
  }

  const double remaining = query.time_limit_s - seconds_since(t0);
  search::SearchOptions o;
  o.time_limit_s = std::max(0.0, remaining);
  if (query.max_expansions != 0) {
    // What the escape left of the budget; an escape that used all of it
    // leaves none (0 would mean no budget).
    if (result.stats.expansions >= query.max_expansions) {
      result.status = PlanStatus::kTimeout;
      result.stats.budget_exhausted = true;
      result.message = budget_message(query.max_expansions);
      return finish(result);
    }
    o.max_expansions = query.max_expansions - result.stats.expansions;
  }
  o.improve_time_s = query.improve_time_s;
  o.eps_initial = query.eps_initial;
  o.eps_final = query.eps_final;
  o.eps_decrement = query.eps_decrement;
  search::SearchResult sr;
  std::vector<JointVector> path;
  const double before = seconds_since(t0);
  const double before_cpu = sim::thread_cpu_seconds() - cpu0;
  if (query.mode == PlanMode::kArmCartesian) {
    LineLattice graph(lattice, checker, start, std::get<sim::PoseGoal>(query.goal));
    GraphHeuristic<LineLattice> h(graph);
    // One dimension: the first solution is optimal at ε = 1 and cheap.
    o.eps_initial = o.eps_final = 1.0;
    sr = search_.search(graph, h, graph.start(), o);
    for (auto id : sr.path) path.push_back(graph.config(id));
    if (sr.status != search::SearchStatus::kSolved && graph.broken_at() >= 0) {
      result.message = "the line leaves the arm's reach or IK branch at " +
                       std::to_string(graph.broken_at() * lattice.resolution[0]) + " m";
    }
  } else {
    JointLattice graph(lattice, checker, start, query.goal, false);
    GraphHeuristic<JointLattice> h(graph);
    sr = search_.search(graph, h, graph.start(), o);
    for (auto id : sr.path) path.push_back(graph.config(id));
  }
  result.stats.expansions += sr.expansions;
  result.stats.budget_exhausted = sr.budget_exhausted;
  result.stats.time_limit_hit = sr.time_limit_hit;
  result.stats.final_eps = sr.final_eps;
  result.stats.suboptimality_bound = sr.suboptimality_bound;
  if (sr.status != search::SearchStatus::kSolved) {
    result.status =
        sr.status == search::SearchStatus::kTimeout ? PlanStatus::kTimeout : PlanStatus::kNoPath;
    if (sr.budget_exhausted) {
      result.message = budget_message(query.max_expansions);
    } else if (result.message.empty()) {
      result.message = sr.status == search::SearchStatus::kTimeout
                           ? "no solution within the time limit"
                           : "no path: the lattice was exhausted";
    }
    return finish(result);
  }
  result.status = PlanStatus::kSolved;
  result.stats.first_solution_s = before + sr.first_solution_time_s;
  result.stats.first_solution_cpu_s = before_cpu + sr.first_solution_cpu_s;
  result.stats.cost = sr.cost;
  // The line must stay a line; elsewhere drop lattice detours.
  if (query.mode != PlanMode::kArmCartesian) {
    path = sim::shortcut_path(path, checker);
    if (const auto* pg = std::get_if<sim::PoseGoal>(&query.goal))
      aim_at_quickest_goal(path, *pg, lattice, checker);
  }
  result.path = prefix;
  result.path.insert(result.path.end(), path.begin(), path.end());
  result.trajectory = sim::Trajectory::from_waypoints(result.path, robot.all_limits());
  return finish(result);
}

}  // namespace plr::arastar
