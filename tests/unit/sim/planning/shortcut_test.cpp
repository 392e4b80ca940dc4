// Path shortcutting (sim/planning/shortcut.cpp).
#include <gtest/gtest.h>

#include "plr/planning/shortcut.hpp"

namespace plr::planning {
namespace {

using namespace plr::sim;

const RobotModel& robot() {
  static const RobotModel m = load_robot().value();
  return m;
}

JointVector at(double base, double arm1 = 0.0) {
  JointVector q;
  q << base, arm1, -1.0, 2.0, 0.0, 0.5, 0.0, 0.0;
  return q;
}

TEST(Shortcut, StraightRunsCollapseToTheirEnds) {
  const World empty;
  const CollisionChecker checker(robot(), empty);
  const auto out = shortcut_path({at(1.0), at(1.5), at(2.0), at(2.0), at(2.5)}, checker);
  EXPECT_EQ(out, (std::vector<JointVector>{at(1.0), at(2.5)}));
}

TEST(Shortcut, AStaircaseBecomesOneMoveWhereNothingIsInTheWay) {
  const World empty;
  const CollisionChecker checker(robot(), empty);
  const auto out =
      shortcut_path({at(1.0), at(1.2), at(1.2, 0.2), at(1.4, 0.2), at(1.4, 0.4)}, checker);
  EXPECT_EQ(out, (std::vector<JointVector>{at(1.0), at(1.4, 0.4)}));
}

TEST(Shortcut, KeepsTheDetourAroundAnObstacle) {
  // A box in the straight way of the plate; the path goes around it.
  World w;
  Box box;
  box.id = 1;
  box.size = {0.3, 0.3, 0.3};
  const Eigen::Vector3d p0 = robot().plate_pose(at(2.0, -0.6)).translation();
  const Eigen::Vector3d p1 = robot().plate_pose(at(2.0, 0.6)).translation();
  box.pose.translation() = 0.5 * (p0 + p1);
  w.boxes.push_back(box);
  const CollisionChecker checker(robot(), w);
  ASSERT_TRUE(checker.is_valid(at(2.0, -0.6)));
  ASSERT_TRUE(checker.is_valid(at(2.0, 0.6)));
  ASSERT_FALSE(checker.is_motion_valid(at(2.0, -0.6), at(2.0, 0.6)));
  JointVector up_a = at(2.0, -0.6), up_b = at(2.0, 0.6);
  up_a[kArm2] = up_b[kArm2] = -1.6;  // swing over it, arm raised
  ASSERT_TRUE(checker.is_motion_valid(at(2.0, -0.6), up_a));
  ASSERT_TRUE(checker.is_motion_valid(up_a, up_b));
  ASSERT_TRUE(checker.is_motion_valid(up_b, at(2.0, 0.6)));
  const auto out = shortcut_path({at(2.0, -0.6), up_a, up_b, at(2.0, 0.6)}, checker);
  ASSERT_GE(out.size(), 3u);
  for (std::size_t i = 1; i < out.size(); ++i)
    EXPECT_TRUE(checker.is_motion_valid(out[i - 1], out[i])) << "segment " << i;
}

}  // namespace
}  // namespace plr::planning
