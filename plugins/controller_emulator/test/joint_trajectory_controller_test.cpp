// The emulated controller's semantics, step by step in controller time.
#include "joint_trajectory_controller.hpp"

#include <gtest/gtest.h>

namespace plr::emulator {
namespace {

using ros2::GoalStatus;
using ros2::TrajectoryError;

ControllerOptions two_joints(double lag_s = 0.0) {
  ControllerOptions o;
  o.joints = {"a", "b"};
  o.lag_s = lag_s;
  return o;
}

// From (0, 0) to (1, -1) in `duration` s, at rest at both ends.
ros2::TrajectoryGoal move(double duration, std::vector<std::string> names = {"a", "b"}) {
  ros2::TrajectoryGoal g;
  g.joint_names = std::move(names);
  g.points = {{0.0, {0.0, 0.0}, {0.0, 0.0}}, {duration, {1.0, -1.0}, {0.0, 0.0}}};
  g.path_tolerance = {{"a", 0.1}, {"b", 0.1}};
  g.goal_tolerance = {{"a", 0.01}, {"b", 0.01}};
  g.goal_time_tolerance_s = 0.5;
  return g;
}

ros2::GoalId id(std::uint8_t n) {
  ros2::GoalId g{};
  g[0] = n;
  return g;
}

std::optional<FinishedGoal> run(JointTrajectoryController& c, double seconds, double dt = 0.01) {
  for (double t = 0.0; t < seconds; t += dt)
    if (auto done = c.step(dt)) return done;
  return std::nullopt;
}

TEST(JointTrajectoryController, FollowsWithLagAndSucceedsWithinTheGoalTolerance) {
  JointTrajectoryController c(two_joints(0.02), {0.0, 0.0});
  ASSERT_TRUE(c.accept(id(1), move(1.0)));
  ASSERT_FALSE(run(c, 0.5));
  // Halfway the reference is at 0.5; the lagging joint is behind it, not on it.
  EXPECT_LT(c.positions()[0], 0.5);
  EXPECT_GT(c.positions()[0], 0.4);
  auto done = run(c, 1.0);
  ASSERT_TRUE(done);
  EXPECT_EQ(done->result.status, GoalStatus::kSucceeded);
  EXPECT_EQ(done->result.error, TrajectoryError::kSuccessful);
  EXPECT_NEAR(c.positions()[1], -1.0, 0.01);
}

TEST(JointTrajectoryController, TakesTheGoalsJointsInAnyOrderAndRefusesUnknownOnes) {
  JointTrajectoryController c(two_joints(), {0.0, 0.0});
  ASSERT_TRUE(c.accept(id(1), move(1.0, {"b", "a"})));
  ASSERT_TRUE(run(c, 1.2));
  EXPECT_NEAR(c.positions()[0], -1.0, 1e-9);  // "b"'s positions went to joint b
  auto bad = c.accept(id(2), move(1.0, {"a", "c"}));
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("INVALID_JOINTS: no joint 'c'"), std::string::npos);
}

TEST(JointTrajectoryController, ANewGoalPreemptsTheActiveOne) {
  JointTrajectoryController c(two_joints(), {0.0, 0.0});
  ASSERT_TRUE(c.accept(id(1), move(1.0)));
  run(c, 0.3);
  auto second = c.accept(id(2), move(1.0));
  ASSERT_TRUE(second);
  ASSERT_TRUE(*second);
  EXPECT_EQ((*second)->id, id(1));
  EXPECT_EQ((*second)->result.status, GoalStatus::kCanceled);
  EXPECT_EQ((*second)->result.error, TrajectoryError::kInvalidGoal);
  EXPECT_EQ(c.active_goal(), id(2));
}

TEST(JointTrajectoryController, AKnockBeyondThePathToleranceAbortsAndHoldsPosition) {
  JointTrajectoryController c(two_joints(0.02), {0.0, 0.0});
  ASSERT_TRUE(c.accept(id(1), move(2.0)));
  run(c, 0.5);
  ASSERT_TRUE(c.knock_joint("b", 0.3));
  auto done = run(c, 0.1);
  ASSERT_TRUE(done);
  EXPECT_EQ(done->result.status, GoalStatus::kAborted);
  EXPECT_EQ(done->result.error, TrajectoryError::kPathToleranceViolated);
  EXPECT_NE(done->result.error_string.find("joint b"), std::string::npos);
  const auto held = c.positions();
  run(c, 1.0);
  EXPECT_NEAR(c.positions()[0], held[0], 0.02);  // it stays (the lag settles its last step)
  EXPECT_NEAR(c.positions()[1], held[1], 0.02);
}

TEST(JointTrajectoryController, AStuckJointEndsInAGoalToleranceViolation) {
  ControllerOptions o = two_joints();
  JointTrajectoryController c(o, {0.0, 0.0});
  ros2::TrajectoryGoal g = move(1.0);
  g.path_tolerance.clear();  // only the goal is checked
  ASSERT_TRUE(c.accept(id(1), g));
  run(c, 0.5);
  ASSERT_TRUE(c.stick_joint("a"));
  auto done = run(c, 3.0);
  ASSERT_TRUE(done);
  EXPECT_EQ(done->result.error, TrajectoryError::kGoalToleranceViolated);
  EXPECT_GE(c.now(), 1.5);  // not before end + goal_time_tolerance
}

TEST(JointTrajectoryController, ALateStartViolatesThePathTolerance) {
  JointTrajectoryController c(two_joints(), {0.0, 0.0});
  c.delay_next_start(0.5);
  ASSERT_TRUE(c.accept(id(1), move(1.0)));
  auto done = run(c, 1.0);
  ASSERT_TRUE(done);
  EXPECT_EQ(done->result.error, TrajectoryError::kPathToleranceViolated);
  EXPECT_LT(c.now(), 0.5);
}

TEST(JointTrajectoryController, CancelHoldsWhereTheJointsAre) {
  JointTrajectoryController c(two_joints(), {0.0, 0.0});
  ASSERT_TRUE(c.accept(id(1), move(1.0)));
  run(c, 0.5);
  auto done = c.cancel(id(1));
  ASSERT_TRUE(done);
  EXPECT_EQ(done->result.status, GoalStatus::kCanceled);
  const double at = c.positions()[0];
  run(c, 1.0);
  EXPECT_DOUBLE_EQ(c.positions()[0], at);
  EXPECT_FALSE(c.cancel(id(1)));  // no longer active
}

TEST(JointTrajectoryController, RefusesPointsThatDoNotAdvanceInTime) {
  JointTrajectoryController c(two_joints(), {0.0, 0.0});
  ros2::TrajectoryGoal g = move(1.0);
  g.points[1].time_s = 0.0;
  auto r = c.accept(id(1), g);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("INVALID_GOAL: point 1"), std::string::npos);
}

}  // namespace
}  // namespace plr::emulator
