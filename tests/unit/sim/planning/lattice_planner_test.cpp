// The ARA* lattice planner in-process, where it differs from any planner
// (what every planner does is the planner conformance suite's): lattice
// exhaustion against the time limit, budgets that end improvement.
#include <gtest/gtest.h>

#include <cmath>

#include "plr/planning/lattice_planner.hpp"
#include "plr/sim/collision.hpp"
#include "plr/sim/shipped_files.hpp"

using namespace plr::sim;
using namespace plr::planning;

namespace {

const RobotModel& robot() {
  static const RobotModel m = load_robot().value();
  return m;
}

JointVector home(double base) {
  JointVector q;
  q << base, 0.0, -1.0, 2.0, 0.0, 0.5, 0.0, 0.0;
  return q;
}

// A wall of 0.4 m boxes across the trailer, front face at x = face; 5
// columns, the middle one centred on the trailer axis.
World wall(double face, int rows = 5) {
  World w;
  std::uint32_t id = 1;
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < 5; ++c) {
      Box b;
      b.id = id++;
      b.size = Eigen::Vector3d(0.4, 0.4, 0.4);
      b.pose.translation() = Eigen::Vector3d(face + 0.2, 0.405 * (c - 2), 0.2 + 0.405 * r);
      w.boxes.push_back(b);
    }
  }
  return w;
}

LatticePlanner& arastar() {
  static LatticePlanner p(
      LatticeConfig::from_file(shipped_file("robots/unloader_lattice.yaml").value()).value());
  return p;
}

PlanQuery pose_query(PlanMode mode, const JointVector& start, const Eigen::Vector3d& p,
                     double yaw) {
  PlanQuery q;
  q.mode = mode;
  q.start = start;
  PoseGoal g;
  g.target = {p, yaw};
  q.goal = g;
  return q;
}

PlanQuery joint_query(PlanMode mode, const JointVector& start, const JointVector& goal) {
  PlanQuery q;
  q.mode = mode;
  q.start = start;
  JointGoal g;
  g.q = goal;
  q.goal = g;
  return q;
}

}  // namespace

TEST(Arastar, ExhaustedLatticeIsNoPathAndALargeOneTimesOut) {
  // A floor-to-ceiling wall across the trailer; valid goals behind it.
  World w;
  Box wall;
  wall.id = 1;
  wall.size = Eigen::Vector3d(0.4, 2.48, 2.68);
  wall.pose.translation() = Eigen::Vector3d(3.2, 0.0, 1.345);
  w.boxes.push_back(wall);
  CollisionChecker cc(robot(), w);
  ASSERT_TRUE(cc.is_valid(home(1.0)));
  ASSERT_TRUE(cc.is_valid(home(5.0)));

  // M5: the base line is exhausted on this side of the wall.
  PlanQuery base = joint_query(PlanMode::kBaseLine, home(1.0), home(5.0));
  base.time_limit_s = 2.0;
  const PlanResult nb = arastar().plan(base, cc);
  EXPECT_EQ(nb.status, PlanStatus::kNoPath) << nb.message;
  EXPECT_FALSE(nb.stats.time_limit_hit);

  // M2: the lattice is too large to exhaust; the time limit ends it.
  PlanQuery arm = pose_query(PlanMode::kArmBase, home(1.0), Eigen::Vector3d(5.2, 0.0, 1.2), 0.0);
  arm.time_limit_s = 0.5;
  const PlanResult na = arastar().plan(arm, cc);
  EXPECT_EQ(na.status, PlanStatus::kTimeout) << na.message;
  EXPECT_EQ(na.message, "no solution within the time limit");
  EXPECT_TRUE(na.stats.time_limit_hit);
  EXPECT_TRUE(na.path.empty());
}

// ARA* with a budget that ends it while it improves: the last completed
// iteration's solution, the same every time.
TEST(Arastar, BudgetEndingTheImprovementReturnsTheLastSolution) {
  const World w = wall(5.0);
  PlanQuery q = pose_query(PlanMode::kArmBase, home(2.0), Eigen::Vector3d(4.85, 0.4, 1.8), 0.0);
  q.improve_time_s = 10.0;
  q.max_expansions = 400;
  CollisionChecker cc(robot(), w);
  const PlanResult cut = arastar().plan(q, cc);
  ASSERT_EQ(cut.status, PlanStatus::kSolved) << cut.message;
  EXPECT_TRUE(cut.stats.budget_exhausted);
  EXPECT_FALSE(cut.stats.time_limit_hit);
  EXPECT_EQ(cut.stats.expansions, q.max_expansions);
  EXPECT_GT(cut.stats.final_eps, q.eps_final);
  const PlanResult again = arastar().plan(q, cc);
  EXPECT_EQ(again.path, cut.path);
  EXPECT_EQ(again.stats.final_eps, cut.stats.final_eps);
}
