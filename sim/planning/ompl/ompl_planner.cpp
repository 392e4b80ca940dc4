#include "plr/planning/ompl_planner.hpp"

#include "plr/planning/shortcut.hpp"

#include <ompl/base/DiscreteMotionValidator.h>
#include <ompl/base/MotionValidator.h>
#include <ompl/base/ProblemDefinition.h>
#include <ompl/base/goals/GoalStates.h>
#include <ompl/base/spaces/RealVectorStateSpace.h>
#include <ompl/geometric/PathGeometric.h>
#include <ompl/geometric/planners/rrt/RRTConnect.h>
#include <ompl/util/Console.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <mutex>
#include <random>

namespace plr::ompl_planner {

namespace ob = ompl::base;
namespace og = ompl::geometric;
using planning::PlanMode;
using planning::PlanResult;
using planning::PlanStatus;
using sim::JointVector;

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

// Maps planning-space states to full configurations.
class Mapping {
 public:
  virtual ~Mapping() = default;
  // False if the state has no configuration (M4: no IK).
  virtual bool to_joint_vector(const ob::State* s, JointVector& q) const = 0;
};

class JointMapping final : public Mapping {
 public:
  JointMapping(std::vector<int> joints, const JointVector& fixed)
      : joints_(std::move(joints)), fixed_(fixed) {}
  bool to_joint_vector(const ob::State* s, JointVector& q) const override {
    const auto* v = s->as<ob::RealVectorStateSpace::StateType>();
    q = fixed_;
    for (std::size_t i = 0; i < joints_.size(); ++i) q[joints_[i]] = v->values[i];
    return true;
  }

 private:
  std::vector<int> joints_;
  JointVector fixed_;
};

// M4: progress s in [0, 1] along the plate's line; the IK solution nearest
// to the start configuration keeps one branch along the line.
class LineMapping final : public Mapping {
 public:
  LineMapping(const sim::RobotModel& robot, const JointVector& start, const sim::PlateTarget& goal)
      : robot_(robot), start_(start), from_(robot.plate_target(start)), to_(goal) {
    to_.yaw = from_.yaw + std::remainder(to_.yaw - from_.yaw, 2.0 * M_PI);
  }
  bool to_joint_vector(const ob::State* s, JointVector& q) const override {
    const double t = s->as<ob::RealVectorStateSpace::StateType>()->values[0];
    const sim::PlateTarget p{from_.position + t * (to_.position - from_.position),
                             from_.yaw + t * (to_.yaw - from_.yaw)};
    const auto sols = robot_.arm_ik(p, start_);
    if (sols.empty()) return false;
    q = sols.front();
    return true;
  }
  double length() const { return (to_.position - from_.position).norm(); }

 private:
  const sim::RobotModel& robot_;
  JointVector start_;
  sim::PlateTarget from_, to_;
};

class Validity final : public ob::StateValidityChecker {
 public:
  Validity(const ob::SpaceInformationPtr& si, const Mapping& map, const sim::CollisionChecker& cc)
      : ob::StateValidityChecker(si), map_(map), cc_(cc) {}
  bool isValid(const ob::State* s) const override {
    JointVector q;
    return map_.to_joint_vector(s, q) && cc_.is_valid(q);
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
    JointVector qa, qb;
    const bool ok =
        map_.to_joint_vector(a, qa) && map_.to_joint_vector(b, qb) && cc_.is_motion_valid(qa, qb);
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

// Uniform sampling with a seed of our choosing instead of one drawn from
// OMPL's process-wide sequence.
class SeededSampler final : public ob::RealVectorStateSampler {
 public:
  SeededSampler(const ob::StateSpace* space, std::uint32_t seed) : RealVectorStateSampler(space) {
    rng_.setLocalSeed(seed);
  }
};

// FNV-1a over what defines a query (the world is the checker's).
class QueryHash {
 public:
  template <class T>
  void add(const T& v) {
    unsigned char bytes[sizeof(T)];
    std::memcpy(bytes, &v, sizeof(T));
    for (unsigned char b : bytes) h_ = (h_ ^ b) * 1099511628211ull;
  }
  void add(const JointVector& q) {
    for (int i = 0; i < sim::kNumJoints; ++i) add(q[i]);
  }
  std::uint64_t value() const { return h_; }

 private:
  std::uint64_t h_ = 1469598103934665603ull;
};

std::uint32_t query_seed(const planning::PlanQuery& q, std::uint32_t seed) {
  QueryHash h;
  h.add(seed);
  h.add(static_cast<int>(q.mode));
  h.add(q.start);
  h.add(q.goal.index());
  if (const auto* jg = std::get_if<planning::JointGoal>(&q.goal)) {
    h.add(jg->q);
    h.add(jg->tolerance);
  } else if (const auto* pg = std::get_if<planning::PoseGoal>(&q.goal)) {
    for (int i = 0; i < 3; ++i) h.add(pg->target.position[i]);
    h.add(pg->target.yaw);
  }
  for (const sim::Box& b : q.held_boxes) h.add(b.id);
  for (std::uint32_t id : q.ignored_boxes) h.add(id);
  const std::uint64_t v = h.value();
  // OMPL treats seed 0 as "none".
  return std::max<std::uint32_t>(1u, static_cast<std::uint32_t>(v ^ (v >> 32)));
}

// Randomised shortcutting between points inside segments (what OMPL's
// PathSimplifier::shortcut_path does), on the query's own generator. Lengths
// are joint-space distances scaled by velocity limits.
std::vector<JointVector> random_shortcut(std::vector<JointVector> path,
                                         const sim::CollisionChecker& cc, std::mt19937& rng) {
  const sim::RobotModel& robot = cc.robot();
  auto dist = [&](const JointVector& a, const JointVector& b) {
    double s = 0.0;
    for (int j = 0; j < sim::kNumJoints; ++j) {
      const double d = (b[j] - a[j]) / robot.limits(j).velocity;
      s += d * d;
    }
    return std::sqrt(s);
  };
  const std::size_t max_steps = 2 * path.size() + 10;
  std::size_t failures = 0;
  for (std::size_t step = 0; step < max_steps && failures < path.size() && path.size() > 2;
       ++step) {
    std::vector<double> acc{0.0};
    for (std::size_t i = 1; i < path.size(); ++i)
      acc.push_back(acc.back() + dist(path[i - 1], path[i]));
    std::uniform_real_distribution<double> u(0.0, acc.back());
    double a = u(rng), b = u(rng);
    if (a > b) std::swap(a, b);
    auto at = [&](double s, std::size_t& seg) {
      seg = static_cast<std::size_t>(std::upper_bound(acc.begin(), acc.end(), s) - acc.begin());
      seg = std::clamp<std::size_t>(seg, 1, path.size() - 1) - 1;
      const double len = acc[seg + 1] - acc[seg];
      const double f = len > 0.0 ? (s - acc[seg]) / len : 0.0;
      return JointVector(path[seg] + f * (path[seg + 1] - path[seg]));
    };
    std::size_t ia = 0, ib = 0;
    const JointVector pa = at(a, ia), pb = at(b, ib);
    if (ia == ib || !cc.is_motion_valid(pa, pb)) {
      ++failures;
      continue;
    }
    failures = 0;
    std::vector<JointVector> next(path.begin(), path.begin() + static_cast<std::ptrdiff_t>(ia) + 1);
    next.push_back(pa);
    next.push_back(pb);
    next.insert(next.end(), path.begin() + static_cast<std::ptrdiff_t>(ib) + 1, path.end());
    path = std::move(next);
  }
  return path;
}

}  // namespace

OmplPlanner::OmplPlanner(const Options& options) : options_(options) {
  static std::once_flag once;
  std::call_once(once, [] { ompl::msg::setLogLevel(ompl::msg::LOG_WARN); });
}

PlanResult OmplPlanner::do_plan(const planning::PlanQuery& query, sim::CollisionChecker& checker) {
  const auto t0 = std::chrono::steady_clock::now();
  const double cpu0 = thread_cpu_seconds();
  const sim::RobotModel& robot = checker.robot();
  const bool line = query.mode == PlanMode::kArmCartesian;
  const std::vector<int> joints = planning::planned_joints(query.mode);
  const unsigned dims = line ? 1u : static_cast<unsigned>(joints.size());
  auto space = std::make_shared<ob::RealVectorStateSpace>(dims);
  ob::RealVectorBounds bounds(dims);
  std::unique_ptr<Mapping> mapping;
  if (line) {
    bounds.setLow(0.0);
    bounds.setHigh(1.0);
    const auto& pg = std::get<planning::PoseGoal>(query.goal);
    mapping = std::make_unique<LineMapping>(robot, query.start, pg.target);
  } else {
    for (unsigned i = 0; i < dims; ++i) {
      bounds.setLow(i, robot.limits(joints[i]).lower);
      bounds.setHigh(i, robot.limits(joints[i]).upper);
    }
    mapping = std::make_unique<JointMapping>(joints, query.start);
  }
  space->setBounds(bounds);
  const std::uint32_t seed = query_seed(query, options_.seed);
  space->setStateSamplerAllocator([seed, n = 0u](const ob::StateSpace* sp) mutable {
    return std::make_shared<SeededSampler>(sp, seed + n++);
  });
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

  auto to_state = [&](const JointVector& q, ob::ScopedState<>& s) {
    for (unsigned i = 0; i < dims; ++i) s[i] = q[joints[i]];
  };
  ob::ScopedState<> start(space);
  if (line) {
    start[0] = 0.0;
  } else {
    to_state(query.start, start);
  }
  auto pdef = std::make_shared<ob::ProblemDefinition>(si);
  pdef->addStartState(start);
  auto goals = std::make_shared<ob::GoalStates>(si);
  if (line) {
    ob::ScopedState<> g(space);
    g[0] = 1.0;
    if (!si->isValid(g.get()))
      return (fail(PlanStatus::kGoalInvalid, "goal: no valid IK at the line's end"));
    goals->addState(g);
  } else if (const auto* jg = std::get_if<planning::JointGoal>(&query.goal)) {
    JointVector q = query.start;
    for (int j : joints) q[j] = jg->q[j];
    if (!checker.is_valid(q))
      return (fail(PlanStatus::kGoalInvalid, "goal: " + checker.describe_collision(q)));
    ob::ScopedState<> g(space);
    to_state(q, g);
    goals->addState(g);
  } else {
    const auto& pg = std::get<planning::PoseGoal>(query.goal);
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
      JointVector seed = query.start;
      seed[sim::kBaseX] = b;
      for (const JointVector& q : robot.arm_ik(pg.target, seed)) {
        if (!checker.is_valid(q)) continue;
        ob::ScopedState<> g(space);
        to_state(q, g);
        goals->addState(g);
      }
      if (goals->getStateCount() >= 8) break;
    }
    if (goals->getStateCount() == 0) {
      return (fail(PlanStatus::kGoalInvalid, "goal: no collision-free arm IK solution"));
    }
  }
  pdef->setGoal(goals);

  og::RRTConnect rrt(si);
  if (options_.range > 0.0) rrt.setRange(options_.range);
  rrt.setProblemDefinition(pdef);
  rrt.setup();
  const auto deadline = t0 + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                 std::chrono::duration<double>(query.time_limit_s));
  // RRTConnect evaluates the condition once per iteration (and while it
  // samples goals), always in the same order: counting evaluations is a
  // load-independent budget.
  std::uint64_t evaluations = 0;
  bool budget_hit = false, time_hit = false;
  const ob::PlannerTerminationCondition ptc([&] {
    ++evaluations;
    budget_hit = query.max_expansions != 0 && evaluations > query.max_expansions;
    time_hit = std::chrono::steady_clock::now() >= deadline;
    return budget_hit || time_hit;
  });
  const ob::PlannerStatus st = rrt.solve(ptc);
  PlanResult result;
  result.stats.expansions = evaluations;
  if (st != ob::PlannerStatus::EXACT_SOLUTION) {
    result.status = PlanStatus::kTimeout;
    result.stats.budget_exhausted = budget_hit;
    result.stats.time_limit_hit = time_hit && !budget_hit;
    result.message = budget_hit ? "no solution within the expansion budget of " +
                                      std::to_string(query.max_expansions)
                                : "no solution within the time limit";
    return result;
  }
  result.stats.first_solution_s = seconds_since(t0);
  result.stats.first_solution_cpu_s = thread_cpu_seconds() - cpu0;
  auto& path = *pdef->getSolutionPath()->as<og::PathGeometric>();
  std::vector<JointVector> configs;
  if (line) {
    // Densify to 1 cm of plate travel so the IK path follows the line.
    const double len = static_cast<const LineMapping&>(*mapping).length();
    path.interpolate(std::max(2u, static_cast<unsigned>(std::ceil(len / 0.01)) + 1));
  }
  for (std::size_t i = 0; i < path.getStateCount(); ++i) {
    JointVector q;
    if (!mapping->to_joint_vector(path.getState(i), q))
      return (fail(PlanStatus::kNoPath, "lost IK on the line"));
    configs.push_back(q);
  }
  if (!line) {
    std::mt19937 rng(seed);
    configs = planning::shortcut_path(random_shortcut(configs, checker, rng), checker);
  }
  result.status = PlanStatus::kSolved;
  result.path = configs;
  double cost = 0.0;
  for (std::size_t i = 1; i < configs.size(); ++i) {
    double t = 0.0;
    for (int j = 0; j < sim::kNumJoints; ++j) {
      t = std::max(t, std::abs(configs[i][j] - configs[i - 1][j]) / robot.limits(j).velocity);
    }
    cost += t;
  }
  result.stats.cost = cost;
  return result;
}

}  // namespace plr::ompl_planner
