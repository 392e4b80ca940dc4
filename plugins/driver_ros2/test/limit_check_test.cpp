// Joint limits from the shipped URDF, checked before anything is sent.
#include "limit_check.hpp"

#include <gtest/gtest.h>

namespace plr::driver {
namespace {

std::vector<planning::TimedPoint> still_then(double t, int joint, double q, double v) {
  planning::TimedPoint a;
  a.position << 0.0, 0.0, -1.0, 2.0, 0.0, 0.5, 0.0, 0.0;
  planning::TimedPoint b = a;
  b.time_s = t;
  b.position[joint] = q;
  b.velocity[joint] = v;
  return {a, b};
}

class LimitCheck : public ::testing::Test {
 protected:
  sim::RobotModel robot_ = *sim::load_robot("");  // the shipped unloader.urdf
};

TEST_F(LimitCheck, AcceptsATrajectoryWithinEveryLimit) {
  EXPECT_TRUE(check_limits(still_then(1.0, sim::kBaseX, 0.3, 0.5), robot_, 0.05));
}

TEST_F(LimitCheck, NamesThePointAndJointOfAPositionBeyondItsLimit) {
  auto r = check_limits(still_then(1.0, sim::kArm2, 1.6, 0.0), robot_, 0.05);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().message,
            "trajectory point 1 (t=1.000 s), joint arm_2: position 1.6000 outside its limits "
            "[-2.2000, 1.3000]");
}

TEST_F(LimitCheck, RefusesAVelocityBeyondItsLimitAndMargin) {
  // base_x: 0.6 m/s; 0.62 is within a 5 % margin, 0.65 is not.
  EXPECT_TRUE(check_limits(still_then(1.0, sim::kBaseX, 0.3, 0.62), robot_, 0.05));
  auto r = check_limits(still_then(1.0, sim::kBaseX, 0.3, 0.65), robot_, 0.05);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("joint base_x: velocity 0.6500 beyond its limit 0.6000"),
            std::string::npos);
}

TEST_F(LimitCheck, RefusesAnAccelerationBeyondItsLimit) {
  // base_x: 0.8 m/s^2; 0.5 m/s reached in 0.1 s is 5 m/s^2.
  auto r = check_limits(still_then(0.1, sim::kBaseX, 0.02, 0.5), robot_, 0.05);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("acceleration 5.0000 beyond its limit 0.8000"),
            std::string::npos);
}

TEST_F(LimitCheck, RefusesTimesThatDoNotAdvance) {
  auto r = check_limits(still_then(0.0, sim::kBaseX, 0.0, 0.0), robot_, 0.05);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("trajectory point 1: time 0.000 s is not after 0.000 s"),
            std::string::npos);
}

}  // namespace
}  // namespace plr::driver
