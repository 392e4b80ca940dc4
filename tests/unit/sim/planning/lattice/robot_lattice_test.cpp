// The robot's search graphs (sim/planning/lattice/robot_lattice.cpp).
#include <gtest/gtest.h>

#include "lattice/robot_lattice.hpp"
#include "plr/sim/shipped_files.hpp"

namespace plr::planning {
namespace {

using namespace plr::sim;

const RobotModel& robot() {
  static const RobotModel m = load_robot().value();
  return m;
}

const LatticeConfig& config() {
  static const LatticeConfig c =
      LatticeConfig::from_file(shipped_file("robots/unloader_lattice.yaml").value()).value();
  return c;
}

TEST(JointLattice, SuccessorsMoveOnlyTheModesJointsAndCostTheirTime) {
  const World empty;
  const CollisionChecker checker(robot(), empty);
  JointVector far = plr::sim::home_configuration(2.0);
  far[kNose1] = 0.0;
  far[kNose3] = 0.3;
  const ModeLattice& m3 = config().modes.at(PlanMode::kNose);
  JointLattice graph(m3, checker, plr::sim::home_configuration(2.0), JointGoal{far, 1e-3}, false);
  std::vector<search::Successor> out;
  graph.successors(graph.start(), out);
  ASSERT_FALSE(out.empty());
  for (const auto& s : out) {
    const JointVector d = graph.config(s.id) - plr::sim::home_configuration(2.0);
    for (int j : {kBaseX, kArm1, kArm2, kArm3, kArm4}) EXPECT_EQ(d[j], 0.0);
    double t = 0.0;
    for (int j : m3.joints) t = std::max(t, std::abs(d[j]) / robot().limits(j).velocity);
    EXPECT_NEAR(s.cost, t, 1e-12);
  }
  EXPECT_FALSE(graph.is_goal(graph.start()));
  // The heuristic is the straight move's time: admissible.
  double t = 0.0;
  for (int j : m3.joints)
    t = std::max(
        t, std::abs(far[j] - plr::sim::home_configuration(2.0)[j]) / robot().limits(j).velocity);
  EXPECT_NEAR(graph.heuristic(graph.start()), t, 1e-12);
}

TEST(JointLattice, ANearJointGoalIsReachedByOneSnap) {
  const World empty;
  const CollisionChecker checker(robot(), empty);
  const JointVector goal = plr::sim::home_configuration(2.3);
  JointLattice graph(config().modes.at(PlanMode::kBaseLine), checker,
                     plr::sim::home_configuration(2.0), JointGoal{goal, 1e-3}, false);
  std::vector<search::Successor> out;
  graph.successors(graph.start(), out);
  ASSERT_EQ(out.size(), 1u) << "a snap within snap_time is the only successor";
  EXPECT_TRUE(graph.is_goal(out[0].id));
  EXPECT_EQ(graph.config(out[0].id), goal);
}

TEST(JointLattice, EscapeGoalsAreFreeStates) {
  World w;
  Box b;
  b.id = 1;
  const Eigen::Vector3d plate = robot().plate_pose(plr::sim::home_configuration(2.0)).translation();
  b.pose.translation() = plate + Eigen::Vector3d(0.195, 0.0, 0.0);  // 5 mm into the plate
  w.boxes.push_back(b);
  const CollisionChecker checker(robot(), w);
  ASSERT_FALSE(checker.is_valid(plr::sim::home_configuration(2.0)));
  JointLattice graph(config().modes.at(PlanMode::kEscape), checker,
                     plr::sim::home_configuration(2.0), std::monostate{}, true);
  EXPECT_FALSE(graph.is_goal(graph.start()));
  std::vector<search::Successor> out;
  graph.successors(graph.start(), out);
  bool some_free = false;
  for (const auto& s : out) some_free = some_free || graph.is_goal(s.id);
  EXPECT_TRUE(some_free) << "one step back frees the plate";
}

TEST(LineLattice, StatesFollowTheLine) {
  const World empty;
  const CollisionChecker checker(robot(), empty);
  const JointVector start = plr::sim::home_configuration(2.0);
  const PlateTarget from = robot().plate_target(start);
  PoseGoal goal;
  goal.target = {from.position + Eigen::Vector3d(0.2, 0.0, 0.0), from.yaw};
  LineLattice graph(config().modes.at(PlanMode::kArmCartesian), checker, start, goal);
  std::vector<search::Successor> out;
  graph.successors(graph.start(), out);
  ASSERT_FALSE(out.empty());
  for (const auto& s : out) {
    const Eigen::Vector3d p = robot().plate_pose(graph.config(s.id)).translation();
    EXPECT_NEAR(p.y(), from.position.y(), 0.006);
    EXPECT_NEAR(p.z(), from.position.z(), 0.006);
    EXPECT_GT(p.x(), from.position.x());
  }
  EXPECT_EQ(graph.broken_at(), -1);
}

}  // namespace
}  // namespace plr::planning
