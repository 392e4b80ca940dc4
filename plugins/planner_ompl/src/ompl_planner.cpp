#include "ompl_planner.hpp"

#include <ompl/base/DiscreteMotionValidator.h>
#include <ompl/base/MotionValidator.h>
#include <ompl/base/ProblemDefinition.h>
#include <ompl/base/goals/GoalStates.h>
#include <ompl/base/spaces/RealVectorStateSpace.h>
#include <ompl/geometric/PathGeometric.h>
#include <ompl/geometric/PathSimplifier.h>
#include <ompl/geometric/planners/rrt/RRTConnect.h>
#include <ompl/util/Console.h>
#include <ompl/util/RandomNumbers.h>

#include <chrono>
#include <cmath>
#include <mutex>

namespace plr::ompl_planner {

namespace ob = ompl::base;
namespace og = ompl::geometric;
using sim::Config;
using sim::PlanMode;
using sim::PlanResult;
using sim::PlanStatus;

namespace {

double secondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

PlanResult fail(PlanStatus status, std::string message) {
  PlanResult r;
  r.status = status;
  r.message = std::move(message);
  return r;
}

// Maps planning-space states to full configurations.
class Mapping {
 public:
  virtual ~Mapping() = default;
  // False if the state has no configuration (M4: no IK).
  virtual bool toConfig(const ob::State* s, Config& q) const = 0;
};

class JointMapping final : public Mapping {
 public:
  JointMapping(std::vector<int> joints, const Config& fixed)
      : joints_(std::move(joints)), fixed_(fixed) {}
  bool toConfig(const ob::State* s, Config& q) const override {
    const auto* v = s->as<ob::RealVectorStateSpace::StateType>();
    q = fixed_;
    for (std::size_t i = 0; i < joints_.size(); ++i) q[joints_[i]] = v->values[i];
    return true;
  }

 private:
  std::vector<int> joints_;
  Config fixed_;
};

// M4: progress s in [0, 1] along the plate's line; the IK solution nearest
// to the start configuration keeps one branch along the line.
class LineMapping final : public Mapping {
 public:
  LineMapping(const sim::RobotModel& robot, const Config& start, const sim::PlateTarget& goal)
      : robot_(robot), start_(start), from_(robot.plateTarget(start)), to_(goal) {
    to_.pitch = from_.pitch + std::remainder(to_.pitch - from_.pitch, 2.0 * M_PI);
  }
  bool toConfig(const ob::State* s, Config& q) const override {
    const double t = s->as<ob::RealVectorStateSpace::StateType>()->values[0];
    const sim::PlateTarget p{from_.position + t * (to_.position - from_.position),
                             from_.pitch + t * (to_.pitch - from_.pitch)};
    const auto sols = robot_.armIk(p, start_);
    if (sols.empty()) return false;
    q = sols.front();
    return true;
  }
  double length() const { return (to_.position - from_.position).norm(); }

 private:
  const sim::RobotModel& robot_;
  Config start_;
  sim::PlateTarget from_, to_;
};

class Validity final : public ob::StateValidityChecker {
 public:
  Validity(const ob::SpaceInformationPtr& si, const Mapping& map, const sim::CollisionChecker& cc)
      : ob::StateValidityChecker(si), map_(map), cc_(cc) {}
  bool isValid(const ob::State* s) const override {
    Config q;
    return map_.toConfig(s, q) && cc_.isValid(q);
  }

 private:
  const Mapping& map_;
  const sim::CollisionChecker& cc_;
};

// Joint modes: the checker's conservative sweep, as the lattice planner uses.
class Motion final : public ob::MotionValidator {
 public:
  Motion(const ob::SpaceInformationPtr& si, const Mapping& map, const sim::CollisionChecker& cc)
      : ob::MotionValidator(si), map_(map), cc_(cc) {}
  bool checkMotion(const ob::State* a, const ob::State* b) const override {
    Config qa, qb;
    const bool ok = map_.toConfig(a, qa) && map_.toConfig(b, qb) && cc_.isMotionValid(qa, qb);
    if (ok) {
      ++valid_;
    } else {
      ++invalid_;
    }
    return ok;
  }
  bool checkMotion(const ob::State* a, const ob::State* b,
                   std::pair<ob::State*, double>& last) const override {
    if (checkMotion(a, b)) return true;
    // RRTConnect does not use the partial result; report the start.
    si_->copyState(last.first, a);
    last.second = 0.0;
    return false;
  }

 private:
  const Mapping& map_;
  const sim::CollisionChecker& cc_;
};

}  // namespace

Planner::Planner(const Options& options) : options_(options) {
  static std::once_flag once;
  std::call_once(once, [&] {
    ompl::msg::setLogLevel(ompl::msg::LOG_WARN);
    ompl::RNG::setSeed(options.seed);
  });
}

PlanResult Planner::plan(const sim::PlanQuery& query, sim::CollisionChecker& checker) {
  const auto t0 = std::chrono::steady_clock::now();
  const double cpu0 = sim::threadCpuSeconds();
  const sim::RobotModel& robot = checker.robot();
  if (const std::string err = sim::validateQuery(query, robot); !err.empty()) {
    return fail(PlanStatus::kInvalidRequest, err);
  }
  if (query.mode == PlanMode::kEscape) {
    return fail(PlanStatus::kInvalidRequest,
                "M6 escape is a Dijkstra search: use the ARA* planner");
  }
  const sim::QueryScope scope(checker, query);
  checker.resetStats();
  auto finish = [&](PlanResult r) {
    r.stats.planning_time_s = secondsSince(t0);
    r.stats.collision_checks = checker.stats().state_checks + checker.stats().sweep_checks;
    return r;
  };
  if (!checker.isValid(query.start)) {
    return finish(
        fail(PlanStatus::kStartInvalid, "start: " + checker.describeCollision(query.start)));
  }

  const bool line = query.mode == PlanMode::kArmCartesian;
  const std::vector<int> joints = sim::plannedJoints(query.mode);
  const unsigned dims = line ? 1u : static_cast<unsigned>(joints.size());
  auto space = std::make_shared<ob::RealVectorStateSpace>(dims);
  ob::RealVectorBounds bounds(dims);
  std::unique_ptr<Mapping> mapping;
  if (line) {
    bounds.setLow(0.0);
    bounds.setHigh(1.0);
    const auto& pg = std::get<sim::PoseGoal>(query.goal);
    mapping = std::make_unique<LineMapping>(robot, query.start, pg.target);
  } else {
    for (unsigned i = 0; i < dims; ++i) {
      bounds.setLow(i, robot.limits(joints[i]).lower);
      bounds.setHigh(i, robot.limits(joints[i]).upper);
    }
    mapping = std::make_unique<JointMapping>(joints, query.start);
  }
  space->setBounds(bounds);
  auto si = std::make_shared<ob::SpaceInformation>(space);
  si->setStateValidityChecker(std::make_shared<Validity>(si, *mapping, checker));
  if (line) {
    // Progress is 1-D: check the IK path at 1 cm of plate travel.
    const double len = std::max(0.01, static_cast<const LineMapping&>(*mapping).length());
    si->setStateValidityCheckingResolution(std::min(0.5, 0.01 / len));
  } else {
    si->setMotionValidator(std::make_shared<Motion>(si, *mapping, checker));
  }
  si->setup();

  auto toState = [&](const Config& q, ob::ScopedState<>& s) {
    for (unsigned i = 0; i < dims; ++i) s[i] = q[joints[i]];
  };
  ob::ScopedState<> start(space);
  if (line) {
    start[0] = 0.0;
  } else {
    toState(query.start, start);
  }
  auto pdef = std::make_shared<ob::ProblemDefinition>(si);
  pdef->addStartState(start);
  auto goals = std::make_shared<ob::GoalStates>(si);
  if (line) {
    ob::ScopedState<> g(space);
    g[0] = 1.0;
    if (!si->isValid(g.get()))
      return finish(fail(PlanStatus::kGoalInvalid, "goal: no valid IK at the line's end"));
    goals->addState(g);
  } else if (const auto* jg = std::get_if<sim::JointGoal>(&query.goal)) {
    Config q = query.start;
    for (int j : joints) q[j] = jg->q[j];
    if (!checker.isValid(q))
      return finish(fail(PlanStatus::kGoalInvalid, "goal: " + checker.describeCollision(q)));
    ob::ScopedState<> g(space);
    toState(q, g);
    goals->addState(g);
  } else {
    const auto& pg = std::get<sim::PoseGoal>(query.goal);
    std::vector<double> bases{query.start[sim::kBaseX]};
    if (query.mode == PlanMode::kArmBase) {
      // Base positions from which the plate target is within the arm's reach.
      const sim::JointLimits& lb = robot.limits(sim::kBaseX);
      for (double off = 0.25; off <= 3.0; off += 0.25) {
        for (double b : {query.start[sim::kBaseX] + off, query.start[sim::kBaseX] - off}) {
          if (b >= lb.lower && b <= lb.upper) bases.push_back(b);
        }
      }
    }
    for (double b : bases) {
      Config seed = query.start;
      seed[sim::kBaseX] = b;
      for (const Config& q : robot.armIk(pg.target, seed)) {
        if (!checker.isValid(q)) continue;
        ob::ScopedState<> g(space);
        toState(q, g);
        goals->addState(g);
      }
      if (goals->getStateCount() >= 8) break;
    }
    if (goals->getStateCount() == 0) {
      return finish(fail(PlanStatus::kGoalInvalid, "goal: no collision-free arm IK solution"));
    }
  }
  pdef->setGoal(goals);

  og::RRTConnect rrt(si);
  if (options_.range > 0.0) rrt.setRange(options_.range);
  rrt.setProblemDefinition(pdef);
  rrt.setup();
  const double remaining = std::max(0.0, query.time_limit_s - secondsSince(t0));
  const ob::PlannerStatus st = rrt.solve(ob::timedPlannerTerminationCondition(remaining));
  PlanResult result;
  if (st != ob::PlannerStatus::EXACT_SOLUTION) {
    result.status = PlanStatus::kTimeout;
    result.message = "no solution within the time limit";
    return finish(result);
  }
  result.stats.first_solution_s = secondsSince(t0);
  result.stats.first_solution_cpu_s = sim::threadCpuSeconds() - cpu0;
  auto& path = *pdef->getSolutionPath()->as<og::PathGeometric>();
  std::vector<Config> configs;
  if (line) {
    // Densify to 1 cm of plate travel so the IK path follows the line.
    const double len = static_cast<const LineMapping&>(*mapping).length();
    path.interpolate(std::max(2u, static_cast<unsigned>(std::ceil(len / 0.01)) + 1));
  } else {
    og::PathSimplifier simplifier(si);
    simplifier.shortcutPath(path);
  }
  for (std::size_t i = 0; i < path.getStateCount(); ++i) {
    Config q;
    if (!mapping->toConfig(path.getState(i), q))
      return finish(fail(PlanStatus::kNoPath, "lost IK on the line"));
    configs.push_back(q);
  }
  if (!line) configs = sim::shortcutPath(configs, checker);
  result.status = PlanStatus::kSolved;
  result.path = configs;
  result.trajectory = sim::Trajectory::fromWaypoints(configs, robot.allLimits());
  double cost = 0.0;
  for (std::size_t i = 1; i < configs.size(); ++i) {
    double t = 0.0;
    for (int j = 0; j < sim::kNumJoints; ++j) {
      t = std::max(t, std::abs(configs[i][j] - configs[i - 1][j]) / robot.limits(j).velocity);
    }
    cost += t;
  }
  result.stats.cost = cost;
  return finish(result);
}

}  // namespace plr::ompl_planner
