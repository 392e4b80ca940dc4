// The ARA* lattice planner in-process, where it differs from any planner
// (what every planner does is the planner conformance suite's): the time
// limit, budgets that end improvement, a mode's own budget; and the cheap
// checks before any search (sim/planning/planner.cpp).
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

TEST(Arastar, AWallTheBaseCannotPassIsJudgedBeforeTheSearchAndTheTimeLimitEndsOne) {
  // A floor-to-ceiling wall across the trailer; valid goals behind it. The
  // base line and the arm+base lattice used to be searched (exhausted, or
  // ended by the time limit): the base's own links stop at the wall.
  World w;
  Box wall;
  wall.id = 1;
  wall.size = Eigen::Vector3d(0.4, 2.48, 2.68);
  wall.pose.translation() = Eigen::Vector3d(3.2, 0.0, 1.345);
  w.boxes.push_back(wall);
  CollisionChecker cc(robot(), w);
  ASSERT_TRUE(cc.is_valid(plr::sim::home_configuration(1.0)));
  ASSERT_TRUE(cc.is_valid(plr::sim::home_configuration(5.0)));
  PlanQuery base = joint_query(PlanMode::kBaseLine, plr::sim::home_configuration(1.0),
                               plr::sim::home_configuration(5.0));
  base.time_limit_s = 2.0;
  const PlanResult nb = arastar().plan(base, cc);
  EXPECT_EQ(nb.status, PlanStatus::kGoalInvalid) << nb.message;
  EXPECT_EQ(nb.stats.expansions, 0u);
  EXPECT_NE(nb.message.find("box 1"), std::string::npos) << nb.message;
  PlanQuery arm = pose_query(PlanMode::kArmBase, plr::sim::home_configuration(1.0),
                             Eigen::Vector3d(5.2, 0.0, 1.2), 0.0);
  arm.time_limit_s = 0.5;
  const PlanResult na = arastar().plan(arm, cc);
  EXPECT_EQ(na.status, PlanStatus::kGoalInvalid) << na.message;
  EXPECT_EQ(na.stats.expansions, 0u);

  // With nothing in the way, a time limit too short for the search ends it.
  const World empty;
  CollisionChecker free(robot(), empty);
  PlanQuery far = pose_query(PlanMode::kArmBase, plr::sim::home_configuration(1.0),
                             Eigen::Vector3d(6.2, 0.5, 1.2), 0.0);
  far.time_limit_s = 1e-6;
  const PlanResult nt = arastar().plan(far, free);
  EXPECT_EQ(nt.status, PlanStatus::kTimeout) << nt.message;
  EXPECT_EQ(nt.message, "no solution within the time limit");
  EXPECT_TRUE(nt.stats.time_limit_hit);
  EXPECT_TRUE(nt.path.empty());
}

// ARA* with a budget that ends it while it improves: the last completed
// iteration's solution, the same every time.
TEST(Arastar, BudgetEndingTheImprovementReturnsTheLastSolution) {
  const World w = wall(5.0);
  PlanQuery q = pose_query(PlanMode::kArmBase, plr::sim::home_configuration(2.0),
                           Eigen::Vector3d(4.85, 0.4, 1.8), 0.0);
  // The budget ends it; the time limits are only safety nets, far enough
  // that a loaded machine does not reach them first.
  q.time_limit_s = 600.0;
  q.improve_time_s = 600.0;
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

// Cheap necessary conditions refuse what no search can solve, before it
// starts: no expansion, and a message that says why.
TEST(Arastar, AGoalWithoutAnIkSolutionIsRefusedBeforeAnyExpansion) {
  const World empty;
  CollisionChecker checker(robot(), empty);
  // 4 m up: out of the arm's reach from wherever the base stands.
  for (PlanMode mode : {PlanMode::kArm, PlanMode::kArmBase}) {
    const PlanResult r = arastar().plan(
        pose_query(mode, plr::sim::home_configuration(2.0), Eigen::Vector3d(4.0, 0.0, 4.0), 0.0),
        checker);
    EXPECT_EQ(r.status, PlanStatus::kGoalInvalid) << to_string(mode);
    EXPECT_EQ(r.stats.expansions, 0u) << to_string(mode);
    EXPECT_NE(r.message.find("no arm IK solution"), std::string::npos) << r.message;
  }
  // M2 says over which bases it looked.
  const PlanResult r =
      arastar().plan(pose_query(PlanMode::kArmBase, plr::sim::home_configuration(2.0),
                                Eigen::Vector3d(4.0, 0.0, 4.0), 0.0),
                     checker);
  EXPECT_NE(r.message.find("from any base the base reaches (the base reaches x"), std::string::npos)
      << r.message;
}

TEST(Arastar, AGoalInCollisionIsRefusedBeforeAnyExpansion) {
  const World w = wall(3.0);
  CollisionChecker checker(robot(), w);
  // The plate 10 cm inside the middle box of the second row (id 8): every
  // arm pose, from every base, puts it there.
  const Eigen::Vector3d inside(3.1, 0.0, 0.605);
  for (PlanMode mode : {PlanMode::kArm, PlanMode::kArmBase}) {
    const PlanResult r =
        arastar().plan(pose_query(mode, plr::sim::home_configuration(1.5), inside, 0.0), checker);
    EXPECT_EQ(r.status, PlanStatus::kGoalInvalid) << to_string(mode);
    EXPECT_EQ(r.stats.expansions, 0u) << to_string(mode);
    EXPECT_NE(r.message.find("collides"), std::string::npos) << r.message;
    EXPECT_NE(r.message.find("box "), std::string::npos) << r.message;
  }
  // A joint goal whose arm reaches into the wall.
  const auto into = robot().arm_ik({inside, 0.0}, plr::sim::home_configuration(1.5));
  ASSERT_FALSE(into.empty());
  const PlanResult r = arastar().plan(
      joint_query(PlanMode::kArmBase, plr::sim::home_configuration(1.5), into[0]), checker);
  EXPECT_EQ(r.status, PlanStatus::kGoalInvalid);
  EXPECT_EQ(r.stats.expansions, 0u);
  EXPECT_NE(r.message.find("goal: "), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("box "), std::string::npos) << r.message;
}

TEST(Arastar, ABaseGoalPastABoxTheBaseHitsIsRefusedBeforeAnyExpansion) {
  World w;
  Box b;
  b.id = 7;
  b.pose.translation() = Eigen::Vector3d(3.2, 0.0, 0.2);  // on the floor, across the scoop's path
  w.boxes.push_back(b);
  CollisionChecker checker(robot(), w);
  const JointVector goal = plr::sim::home_configuration(0.5);
  ASSERT_TRUE(checker.is_valid(plr::sim::home_configuration(-0.5)));
  ASSERT_TRUE(checker.is_valid(goal));
  // Forward over the box: the goal is beyond it, the robot there clear of it.
  JointVector far = plr::sim::home_configuration(3.2);
  while (!checker.is_valid(far) && far[kBaseX] < robot().limits(kBaseX).upper) far[kBaseX] += 0.1;
  ASSERT_TRUE(checker.is_valid(far));
  for (PlanMode mode : {PlanMode::kBaseLine, PlanMode::kArmBase}) {
    const PlanResult r =
        arastar().plan(joint_query(mode, plr::sim::home_configuration(0.5), far), checker);
    EXPECT_EQ(r.status, PlanStatus::kGoalInvalid) << to_string(mode);
    EXPECT_EQ(r.stats.expansions, 0u) << to_string(mode);
    EXPECT_NE(r.message.find("the base cannot reach"), std::string::npos) << r.message;
    EXPECT_NE(r.message.find("box 7"), std::string::npos) << r.message;
  }
}

// A mode's own budget ends a search the query would let go on, and the
// answer says whose budget it was.
TEST(Arastar, AModesBudgetEndsTheSearchBeforeTheQuerys) {
  auto config =
      LatticeConfig::from_file(shipped_file("robots/unloader_lattice.yaml").value()).value();
  config.modes.at(PlanMode::kArmBase).max_expansions = 5;
  LatticePlanner small(std::move(config));
  const World empty;
  CollisionChecker checker(robot(), empty);
  // 5 m ahead: the base alone needs more than 5 expansions to get there.
  PlanQuery q = pose_query(PlanMode::kArmBase, plr::sim::home_configuration(1.0),
                           Eigen::Vector3d(6.2, 0.5, 1.2), 0.0);
  q.max_expansions = 5000;
  const PlanResult r = small.plan(q, checker);
  ASSERT_NE(r.status, PlanStatus::kSolved);
  EXPECT_TRUE(r.stats.budget_exhausted);
  EXPECT_LE(r.stats.expansions, 6u);
  EXPECT_NE(r.message.find("M2 arm+base's budget of 5 expansions"), std::string::npos) << r.message;
  const PlanResult full = arastar().plan(q, checker);
  EXPECT_EQ(full.status, PlanStatus::kSolved) << full.message;
  EXPECT_GT(full.stats.expansions, 5u);
}
