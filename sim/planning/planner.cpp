#include "plr/planning/planner.hpp"

#include <time.h>

#include <chrono>
#include <cmath>
#include <optional>

#include <fmt/format.h>

#include "lattice/robot_lattice.hpp"
#include "plr/search/arastar.hpp"

namespace plr::planning {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
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

// Step of the base reachability walk: the M5 lattice's.
constexpr double kBaseStep = 0.01;  // m

// How far base_x can go from `start` along its rail towards `toward`, in
// kBaseStep steps, with the links no arm joint moves (base, nose, scoop)
// clear of the world. Whatever the arm does on the way, a motion that moves
// the base cannot get past where these collide: a relaxed, one-dimensional
// reachability check. `blocked` says what stops it ("" at a joint limit).
struct BaseWalk {
  double reached = 0.0;
  std::string blocked;
};
BaseWalk walk_base(const JointVector& start, double toward, const sim::CollisionChecker& checker) {
  const double dir = toward >= start[sim::kBaseX] ? 1.0 : -1.0;
  const int steps = static_cast<int>(std::ceil(std::abs(toward - start[sim::kBaseX]) / kBaseStep));
  BaseWalk w{start[sim::kBaseX], {}};
  JointVector q = start;
  for (int k = 1; k <= steps; ++k) {
    q[sim::kBaseX] = k == steps ? toward : start[sim::kBaseX] + dir * k * kBaseStep;
    if (std::string hit = checker.base_collision(q); !hit.empty()) {
      w.blocked = std::move(hit);
      return w;
    }
    w.reached = q[sim::kBaseX];
  }
  return w;
}

// The first collision-free configuration whose arm puts the plate on
// `target`, base_x anywhere the base reaches from `start` (nearest first);
// the search could end nowhere else. Beyond the arm's reach of the target
// no base needs to be tried. Empty with `why` set when there is none.
std::optional<JointVector> reachable_pose(const JointVector& start, const PlateTarget& target,
                                          const sim::CollisionChecker& checker, std::string& why) {
  const sim::RobotModel& robot = checker.robot();
  const auto& arm = robot.arm();
  const double reach = arm.upper + arm.fore + arm.plate;
  const sim::JointLimits& lb = robot.limits(sim::kBaseX);
  // Bases from which the arm's yaw axis is within reach of the target in x.
  const double lo = std::max(lb.lower, target.position.x() - arm.yaw_origin.x() - reach);
  const double hi = std::min(lb.upper, target.position.x() - arm.yaw_origin.x() + reach);
  const double b0 = start[sim::kBaseX];
  const BaseWalk back = walk_base(start, std::min(b0, std::max(lo, lb.lower)), checker);
  const BaseWalk ahead = walk_base(start, std::max(b0, std::min(hi, lb.upper)), checker);
  std::size_t ik = 0, colliding = 0;
  std::string first_hit;
  JointVector q = start;
  const int n_back = static_cast<int>(std::floor((b0 - back.reached) / kBaseStep + 1e-9));
  const int n_ahead = static_cast<int>(std::floor((ahead.reached - b0) / kBaseStep + 1e-9));
  for (int k = 0; k <= std::max(n_back, n_ahead); ++k) {
    for (double sign : {1.0, -1.0}) {
      if ((sign > 0 && k > n_ahead) || (sign < 0 && (k > n_back || k == 0))) continue;
      q[sim::kBaseX] = b0 + sign * k * kBaseStep;
      if (q[sim::kBaseX] < lo - 1e-9 || q[sim::kBaseX] > hi + 1e-9) continue;
      for (const JointVector& s : robot.arm_ik(target, q)) {
        ++ik;
        if (checker.is_valid(s)) return s;
        if (++colliding == 1) first_hit = checker.describe_collision(s);
      }
    }
  }
  std::string where =
      fmt::format("the base reaches x {:.2f}..{:.2f} m", back.reached, ahead.reached);
  for (const BaseWalk* w : {&back, &ahead})
    if (!w->blocked.empty()) where += fmt::format(", stopped by {}", w->blocked);
  where += fmt::format("; the arm can reach the target from x {:.2f}..{:.2f} m", lo, hi);
  why = ik == 0 ? "no arm IK solution within joint limits from any base the base reaches (" +
                      where + ")"
                : fmt::format(
                      "every IK solution from the bases the base reaches collides ({} of "
                      "them; {}; {})",
                      ik, first_hit, where);
  return std::nullopt;
}

// kSolved unless the goal can be judged unreachable before any search, by
// cheap necessary conditions: a joint goal in collision; a pose goal
// without a collision-free IK solution (M2: from any base position the base
// reaches); a base goal the base cannot drive to, its own links blocked on
// the way (M2, M5).
PlanResult judge_goal(const PlanQuery& query, const JointVector& start,
                      const sim::CollisionChecker& checker) {
  const sim::RobotModel& robot = checker.robot();
  const bool base_moves = query.mode == PlanMode::kArmBase || query.mode == PlanMode::kBaseLine;
  if (const auto* jg = std::get_if<JointGoal>(&query.goal)) {
    JointVector g = start;
    for (int j : planned_joints(query.mode)) g[j] = jg->q[j];
    if (!checker.is_valid(g))
      return fail(PlanStatus::kGoalInvalid, "goal: " + checker.describe_collision(g));
    if (base_moves && std::abs(g[sim::kBaseX] - start[sim::kBaseX]) > jg->tolerance) {
      const BaseWalk w = walk_base(start, g[sim::kBaseX], checker);
      if (!w.blocked.empty()) {
        return fail(PlanStatus::kGoalInvalid,
                    fmt::format("goal: the base cannot reach x {:.2f} m: it stops at x {:.2f} m "
                                "({})",
                                g[sim::kBaseX], w.reached, w.blocked));
      }
    }
  } else if (const auto* pg = std::get_if<PoseGoal>(&query.goal)) {
    if (query.mode == PlanMode::kArmBase) {
      std::string why;
      if (!reachable_pose(start, pg->target, checker, why))
        return fail(PlanStatus::kGoalInvalid, "goal: " + why);
      return fail(PlanStatus::kSolved, {});
    }
    const auto solutions = robot.arm_ik(pg->target, start);
    if (solutions.empty())
      return fail(PlanStatus::kGoalInvalid, "goal: no arm IK solution within joint limits");
    bool any = false;
    for (const JointVector& q : solutions) any = any || checker.is_valid(q);
    if (!any) {
      return fail(PlanStatus::kGoalInvalid, "goal: every IK solution collides (" +
                                                checker.describe_collision(solutions.front()) +
                                                ")");
    }
  }
  return fail(PlanStatus::kSolved, {});
}

}  // namespace

struct Planner::Escaped {
  PlanStatus status = PlanStatus::kNoPath;
  std::string why;  // when not solved
  std::vector<JointVector> path;
  PlanStats stats;
};

double Planner::thread_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

Planner::Planner(ModeLattice escape)
    : escape_lattice_(std::move(escape)), escape_search_(std::make_unique<search::AraStar>()) {}

Planner::~Planner() = default;

std::vector<PlanMode> Planner::modes() const {
  return {PlanMode::kArm, PlanMode::kArmBase, PlanMode::kNose, PlanMode::kArmCartesian,
          PlanMode::kBaseLine};
}

Planner::Escaped Planner::escape(const PlanQuery& query, sim::CollisionChecker& checker) {
  JointLattice graph(escape_lattice_, checker, query.start, std::monostate{}, true);
  search::ZeroHeuristic zero;
  search::SearchOptions o;
  o.time_limit_s = query.time_limit_s;
  o.max_expansions = query.max_expansions;
  o.first_solution_only = true;
  const auto r = escape_search_->search(graph, zero, graph.start(), o);
  Escaped e;
  e.stats.expansions = r.expansions;
  e.stats.budget_exhausted = r.budget_exhausted;
  e.stats.time_limit_hit = r.time_limit_hit;
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

PlanResult Planner::plan(const PlanQuery& query, sim::CollisionChecker& checker) {
  const auto t0 = Clock::now();
  const double cpu0 = thread_cpu_seconds();
  const sim::RobotModel& robot = checker.robot();
  if (const auto ok = check_query(query, robot); !ok)
    return fail(PlanStatus::kInvalidRequest, ok.error().message);
  const auto handled = modes();
  if (query.mode != PlanMode::kEscape &&
      std::find(handled.begin(), handled.end(), query.mode) == handled.end()) {
    return fail(PlanStatus::kInvalidRequest,
                std::string(to_string(query.mode)) + " is not a mode of planner " + name());
  }
  const QueryScope scope(checker, query);
  checker.reset_stats();
  PlanResult result;
  auto finish = [&](PlanResult r) {
    r.stats.planning_time_s = seconds_since(t0);
    r.stats.collision_checks = checker.stats().state_checks + checker.stats().sweep_checks;
    return r;
  };

  // Leave a start in collision first (M6), then plan from there.
  std::vector<JointVector> prefix;
  PlanQuery rest = query;
  if (!robot.within_limits(query.start)) {
    return finish(
        fail(PlanStatus::kStartInvalid, "start: " + checker.describe_collision(query.start)));
  }
  if (query.mode == PlanMode::kEscape || !checker.is_valid(query.start)) {
    if (query.mode != PlanMode::kEscape && !query.escape_if_start_invalid) {
      return finish(fail(PlanStatus::kStartInvalid,
                         "start in collision: " + checker.describe_collision(query.start)));
    }
    const std::string why = checker.describe_collision(query.start);
    Escaped e = escape(query, checker);
    result.stats = e.stats;
    result.stats.escaped = query.mode != PlanMode::kEscape || !why.empty();
    result.stats.escape_time_s = seconds_since(t0);
    result.stats.escape_cpu_s = thread_cpu_seconds() - cpu0;
    if (e.status != PlanStatus::kSolved) {
      PlanResult r = fail(PlanStatus::kStartInvalid,
                          "start in collision (" + why + ") and no escape found: " + e.why);
      r.stats = result.stats;
      return finish(r);
    }
    prefix = std::move(e.path);
    if (query.mode == PlanMode::kEscape) {
      result.status = PlanStatus::kSolved;
      result.path = std::move(prefix);
      result.stats.first_solution_s = seconds_since(t0);
      result.stats.first_solution_cpu_s = thread_cpu_seconds() - cpu0;
      result.trajectory = sim::Trajectory::from_waypoints(result.path, robot.all_limits());
      return finish(result);
    }
    rest.start = prefix.back();
    prefix.pop_back();  // the rest of the path starts with this state
  }

  if (PlanResult judged = judge_goal(rest, rest.start, checker);
      judged.status != PlanStatus::kSolved) {
    judged.stats = result.stats;
    return finish(judged);
  }

  rest.time_limit_s = std::max(0.0, query.time_limit_s - seconds_since(t0));
  if (query.max_expansions != 0) {
    // What the escape left of the budget; an escape that used all of it
    // leaves none (0 would mean no budget).
    if (result.stats.expansions >= query.max_expansions) {
      result.status = PlanStatus::kTimeout;
      result.stats.budget_exhausted = true;
      result.message = budget_message(query.max_expansions);
      return finish(result);
    }
    rest.max_expansions = query.max_expansions - result.stats.expansions;
  }
  const double before = seconds_since(t0);
  const double before_cpu = thread_cpu_seconds() - cpu0;
  PlanResult planned = do_plan(rest, checker);
  planned.stats.expansions += result.stats.expansions;
  planned.stats.escaped = result.stats.escaped;
  planned.stats.escape_time_s = result.stats.escape_time_s;
  planned.stats.escape_cpu_s = result.stats.escape_cpu_s;
  if (planned.status != PlanStatus::kSolved) {
    // The query's budget, unless the planner's own for the mode was smaller
    // (and said so).
    if (planned.stats.budget_exhausted && planned.message.find("budget") == std::string::npos)
      planned.message = budget_message(query.max_expansions);
    planned.path.clear();
    planned.trajectory = {};
    return finish(planned);
  }
  planned.stats.first_solution_s += before;
  planned.stats.first_solution_cpu_s += before_cpu;
  prefix.insert(prefix.end(), planned.path.begin(), planned.path.end());
  planned.path = std::move(prefix);
  planned.trajectory = sim::Trajectory::from_waypoints(planned.path, robot.all_limits());
  return finish(planned);
}

}  // namespace plr::planning
