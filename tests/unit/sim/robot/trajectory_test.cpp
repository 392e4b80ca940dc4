// Time parameterisation of joint-space paths (sim/robot/trajectory.cpp).
#include <gtest/gtest.h>

#include <cmath>

#include "plr/sim/trajectory.hpp"

namespace plr::sim {
namespace {

const RobotModel& robot() {
  static const RobotModel m = load_robot().value();
  return m;
}

void expect_within_limits(const Trajectory& traj) {
  const Limits& lim = robot().all_limits();
  for (const auto& [t, s] : traj.sampled(0.005)) {
    for (int j = 0; j < kNumJoints; ++j) {
      EXPECT_GE(s.position[j], lim[j].lower - 1e-9) << kJointNames[j] << " t=" << t;
      EXPECT_LE(s.position[j], lim[j].upper + 1e-9) << kJointNames[j] << " t=" << t;
      EXPECT_LE(std::abs(s.velocity[j]), lim[j].velocity + 1e-9) << kJointNames[j] << " t=" << t;
      EXPECT_LE(std::abs(s.acceleration[j]), lim[j].acceleration + 1e-9)
          << kJointNames[j] << " t=" << t;
    }
  }
}

TEST(Trajectory, TrapezoidRespectsLimitsAndReachesWaypoints) {
  const Limits& lim = robot().all_limits();
  const std::vector<JointVector> wps = {plr::sim::home_configuration(1.0),
                                        plr::sim::home_configuration(3.0),
                                        plr::sim::home_configuration(2.6)};
  const Trajectory t = Trajectory::from_waypoints(wps, lim);
  EXPECT_NEAR(t.sample(t.waypoint_time(1)).position[kBaseX], 3.0, 1e-9);
  EXPECT_LT((t.sample(t.duration()).position - wps.back()).norm(), 1e-12);
  // 2 m at 0.6 m/s, 0.8 m/s^2: 2/0.6 + 0.6/0.8 s.
  EXPECT_NEAR(t.waypoint_time(1), 2.0 / 0.6 + 0.6 / 0.8, 1e-9);
  // 0.4 m: triangular (0.6^2 / 0.8 > 0.4), 2 sqrt(0.4 / 0.8) s.
  EXPECT_NEAR(t.duration() - t.waypoint_time(1), 2.0 * std::sqrt(0.4 / 0.8), 1e-9);
  expect_within_limits(t);
  EXPECT_NEAR(segment_duration(wps[0], wps[1], lim), t.waypoint_time(1), 1e-12);
}

TEST(Trajectory, JointsAreSynchronisedOnTheStraightSegment) {
  JointVector a = plr::sim::home_configuration(1.0), b = plr::sim::home_configuration(1.5);
  b[kArm1] = 0.8;  // the arm's yaw moves too
  const Trajectory t = Trajectory::from_waypoints({a, b}, robot().all_limits());
  for (const auto& [time, s] : t.sampled(0.05)) {
    // Every joint has covered the same fraction of its way.
    const double f_base = (s.position[kBaseX] - a[kBaseX]) / (b[kBaseX] - a[kBaseX]);
    const double f_arm = (s.position[kArm1] - a[kArm1]) / (b[kArm1] - a[kArm1]);
    EXPECT_NEAR(f_base, f_arm, 1e-9) << "t=" << time;
  }
  expect_within_limits(t);
}

TEST(Trajectory, OneWaypointStandsStill) {
  const Trajectory t =
      Trajectory::from_waypoints({plr::sim::home_configuration(2.0)}, robot().all_limits());
  EXPECT_EQ(t.duration(), 0.0);
  EXPECT_EQ(t.sample(0.0).position, plr::sim::home_configuration(2.0));
}

}  // namespace
}  // namespace plr::sim
