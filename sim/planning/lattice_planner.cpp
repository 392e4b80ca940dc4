#include "plr/planning/lattice_planner.hpp"

#include <algorithm>

#include <fmt/format.h>

#include "lattice/experience.hpp"
#include "lattice/robot_lattice.hpp"
#include "plr/planning/shortcut.hpp"
#include "plr/search/arastar.hpp"

namespace plr::planning {
namespace {

// A pose goal is met by many configurations: each IK branch, and with the
// base planned, every base position from which the arm reaches the target.
// The search ends at the first one it meets; the path's last move is
// re-aimed at the one it reaches soonest.
void aim_at_quickest_goal(std::vector<JointVector>& path, const PoseGoal& goal,
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

LatticePlanner::LatticePlanner(LatticeConfig config)
    : Planner(config.modes.at(PlanMode::kEscape)),
      config_(std::move(config)),
      search_(std::make_unique<search::AraStar>()) {}

LatticePlanner::~LatticePlanner() = default;

void LatticePlanner::set_experience(bool enabled) {
  config_.experience.enabled = enabled;
  if (!enabled) clear_experience();
}

void LatticePlanner::clear_experience() {
  experience_.clear();
}

std::size_t LatticePlanner::experience_paths(PlanMode mode) const {
  const auto it = experience_.find(mode);
  return it == experience_.end() ? 0 : it->second->paths().size();
}

PlanResult LatticePlanner::do_plan(const PlanQuery& query, sim::CollisionChecker& checker) {
  const ModeLattice& lattice = config_.modes.at(query.mode);
  const JointVector& start = query.start;
  PlanResult result;
  search::SearchOptions o;
  o.time_limit_s = query.time_limit_s;
  // The smaller of the query's budget and the mode's; 0 is no budget.
  const bool mode_budget =
      lattice.max_expansions != 0 &&
      (query.max_expansions == 0 || lattice.max_expansions < query.max_expansions);
  o.max_expansions = mode_budget ? lattice.max_expansions : query.max_expansions;
  o.improve_time_s = query.improve_time_s;
  o.eps_initial = query.eps_initial;
  o.eps_final = query.eps_final;
  o.eps_decrement = query.eps_decrement;
  search::SearchResult sr;
  std::vector<JointVector> path;
  const bool experience = config_.experience.enabled;
  ExperienceStore* store = nullptr;
  if (query.mode == PlanMode::kArmCartesian) {
    LineLattice graph(lattice, checker, start, std::get<PoseGoal>(query.goal));
    GraphHeuristic<LineLattice> h(graph);
    // One dimension: the first solution is optimal at ε = 1 and cheap.
    o.eps_initial = o.eps_final = 1.0;
    sr = search_->search(graph, h, graph.start(), o);
    for (auto id : sr.path) path.push_back(graph.config(id));
    if (sr.status != search::SearchStatus::kSolved && graph.broken_at() >= 0) {
      result.message = "the line leaves the arm's reach or IK branch at " +
                       std::to_string(graph.broken_at() * lattice.resolution[0]) + " m";
    }
  } else {
    // The recurring motions with long searches: to a pre-grasp (M1, M2),
    // to the drop-off and home (M1).
    const bool recurring = query.mode == PlanMode::kArm || query.mode == PlanMode::kArmBase;
    if (experience && recurring) {
      if (checker.trailer_serial() != trailer_) clear_experience();
      trailer_ = checker.trailer_serial();
      auto& slot = experience_[query.mode];
      if (!slot) slot = std::make_unique<ExperienceStore>(config_.experience.max_paths);
      store = slot.get();
    }
    JointLattice graph(lattice, checker, start, query.goal, false, store,
                       config_.experience.weight);
    GraphHeuristic<JointLattice> h(graph);
    sr = search_->search(graph, h, graph.start(), o);
    path = graph.path_configs(sr.path);
    result.stats.experience_edges = graph.experience_edges();
  }
  result.stats.expansions = sr.expansions;
  result.stats.budget_exhausted = sr.budget_exhausted;
  result.stats.time_limit_hit = sr.time_limit_hit;
  result.stats.final_eps = sr.final_eps;
  result.stats.suboptimality_bound = sr.suboptimality_bound;
  if (sr.status != search::SearchStatus::kSolved) {
    result.status =
        sr.status == search::SearchStatus::kTimeout ? PlanStatus::kTimeout : PlanStatus::kNoPath;
    if (sr.budget_exhausted && mode_budget) {
      result.message = fmt::format("no solution within {}'s budget of {} expansions",
                                   to_string(query.mode), lattice.max_expansions);
    } else if (result.message.empty()) {
      result.message = sr.status == search::SearchStatus::kTimeout
                           ? "no solution within the time limit"
                           : "no path: the lattice was exhausted";
    }
    return result;
  }
  result.status = PlanStatus::kSolved;
  result.stats.first_solution_s = sr.first_solution_time_s;
  result.stats.first_solution_cpu_s = sr.first_solution_cpu_s;
  result.stats.cost = sr.cost;
  // The line must stay a line; elsewhere drop lattice detours.
  if (query.mode != PlanMode::kArmCartesian) {
    path = shortcut_path(path, checker);
    if (const auto* pg = std::get_if<PoseGoal>(&query.goal))
      aim_at_quickest_goal(path, *pg, lattice, checker);
  }
  if (store != nullptr) store->add(path);
  result.path = std::move(path);
  return result;
}

}  // namespace plr::planning
