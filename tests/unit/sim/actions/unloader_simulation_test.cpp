// The robot's motions executed on the physics (sim/actions/unloader_simulation.cpp):
// the base's drive has a force limit, so what it can push depends on the
// boxes' absolute masses.
#include "plr/actions/unloader_simulation.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "plr/sim/generators.hpp"
#include "plr/sim/robot_links.hpp"

namespace plr::actions {
namespace {

const sim::RobotModel& robot() {
  static const sim::RobotModel m = sim::load_robot().value();
  return m;
}

// A block of 0.4 m boxes, 3 wide, 2 deep and 3 high, 5 cm ahead of what the
// robot has at its height at q.
sim::World block_ahead_of(const sim::JointVector& q, double mass) {
  double front = -1e9;
  for (const sim::LinkGeometry& g : sim::robot_link_geometry(robot(), q)) {
    const Eigen::Vector3d e = g.pose.linear().cwiseAbs() * (0.5 * g.size);
    if (g.pose.translation().z() - e.z() < 1.25)
      front = std::max(front, g.pose.translation().x() + e.x());
  }
  sim::World w;
  w.trailer.depth = 8.0;
  std::uint32_t id = 1;
  for (int depth = 0; depth < 2; ++depth)
    for (int col = -1; col <= 1; ++col)
      for (int row = 0; row < 3; ++row) {
        sim::Box b;
        b.id = id++;
        b.size = {0.4, 0.4, 0.4};
        b.mass = mass;
        b.pose.translation() =
            Eigen::Vector3d(front + 0.05 + 0.2 + 0.4 * depth, 0.41 * col, 0.2 + 0.4 * row);
        w.boxes.push_back(b);
      }
  return w;
}

// The base drives 0.6 m forward at 0.2 m/s, everything else still.
Motion drive_forward(const sim::JointVector& q) {
  Motion m;
  m.conveyor = false;
  for (int k = 0; k <= 30; ++k) {
    planning::TimedPoint p;
    p.time_s = 0.1 * k;
    p.position = q;
    p.position[sim::kBaseX] += 0.02 * k;
    p.velocity[sim::kBaseX] = 0.2;
    m.points.push_back(p);
  }
  return m;
}

TEST(BaseDrive, AHeavyBlockStallsThePushALightOneLetsThrough) {
  sim::JointVector q = home_configuration();
  q[sim::kBaseX] = 2.0;
  // Light: 18 boxes of 5 kg slide ahead of the robot (about 0.4 x 880 N of
  // floor friction), well within the drive's 2 kN.
  const sim::World light = block_ahead_of(q, 5.0);
  UnloaderSimulation a(robot(), light, q);
  const auto pushed = a.execute(drive_forward(q));
  ASSERT_TRUE(pushed) << pushed.error().message;
  EXPECT_FALSE(pushed->stalled);
  EXPECT_NEAR(a.q()[sim::kBaseX], q[sim::kBaseX] + 0.6, 1e-9);
  EXPECT_GT(pushed->peak_push_force, 100.0);  // it did push the block
  EXPECT_LT(pushed->peak_push_force, UnloaderOptions{}.base_max_push_force);
  EXPECT_FALSE(pushed->moved.empty());

  // The same block, every mass eight times larger: the floor friction alone
  // is over the limit; the base stops where the drive gives up.
  sim::World heavy = light;
  std::vector<std::pair<std::uint32_t, double>> masses;
  for (const sim::Box& b : heavy.boxes) masses.emplace_back(b.id, 8.0 * b.mass);
  ASSERT_TRUE(sim::set_masses(heavy, masses));
  UnloaderSimulation b(robot(), heavy, q);
  const auto stalled = b.execute(drive_forward(q));
  ASSERT_TRUE(stalled) << stalled.error().message;
  EXPECT_TRUE(stalled->stalled);
  EXPECT_GT(stalled->stall_force, UnloaderOptions{}.base_max_push_force);
  EXPECT_LT(stalled->stall_after_s, 3.0);
  EXPECT_LT(b.q()[sim::kBaseX], q[sim::kBaseX] + 0.5);
  // The robot is where it stopped: the next motion starts there.
  Motion back;
  back.conveyor = false;
  planning::TimedPoint p;
  p.position = b.q();
  back.points = {p, p};
  back.points[1].time_s = 0.5;
  back.points[1].position[sim::kBaseX] -= 0.1;
  const auto backed = b.execute(back);
  ASSERT_TRUE(backed) << backed.error().message;
  EXPECT_FALSE(backed->stalled) << backed->stall_force << " N after " << backed->stall_after_s
                                << " s; forward: " << stalled->stall_force << " N after "
                                << stalled->stall_after_s << " s, light "
                                << pushed->peak_push_force;
}

// Straight in joint space from the robot's configuration to `to` in 2 s.
Motion move_to(const sim::JointVector& from, const sim::JointVector& to) {
  Motion m;
  m.conveyor = false;
  for (int k = 0; k <= 20; ++k) {
    planning::TimedPoint p;
    p.time_s = 0.1 * k;
    p.position = from + (to - from) * (k / 20.0);
    p.velocity = (to - from) / 2.0;
    m.points.push_back(p);
  }
  return m;
}

TEST(TrailerContact, IsCountedForTheRobotsShapesNotTheirBoundingCubes) {
  sim::World empty;
  empty.trailer = {2.5, 2.7, 16.0};
  sim::JointVector q = home_configuration();
  q[sim::kBaseX] = 11.0;
  // The arm reaching right, its knuckle (a 9 cm sphere) 3 cm from the side
  // wall: a cube of the sphere's size, turned with the forearm, would reach
  // through the wall.
  sim::JointVector near_wall = q;
  near_wall.segment<4>(sim::kArm1) << -0.802, -0.355, 1.512, 1.404;
  std::vector<Eigen::Isometry3d> poses;
  robot().forward_kinematics(near_wall, poses);
  const double knuckle_y =
      poses[static_cast<std::size_t>(robot().link_index("arm_knuckle"))].translation().y();
  ASSERT_GT(std::abs(knuckle_y) + 0.09 * std::sqrt(2.0), empty.trailer.width / 2);
  ASSERT_LT(std::abs(knuckle_y) + 0.09, empty.trailer.width / 2);
  UnloaderSimulation sim(robot(), empty, q);
  auto out = sim.execute(move_to(q, near_wall));
  ASSERT_TRUE(out) << out.error().message;
  EXPECT_EQ(out->robot_trailer_contacts, 0u);
  // Turned further right, the plate goes into the wall.
  sim::JointVector into_wall = near_wall;
  into_wall[sim::kArm1] = -1.2;
  out = sim.execute(move_to(near_wall, into_wall));
  ASSERT_TRUE(out) << out.error().message;
  EXPECT_EQ(out->robot_trailer_contacts, 1u);
}

TEST(Execute, RefusesATrajectoryWithANonFinitePointAndLeavesTheWorldAsItWas) {
  const sim::JointVector q = home_configuration();
  UnloaderSimulation sim(robot(), block_ahead_of(q, 10.0), q);
  const double before = sim.time();
  Motion nan_position = drive_forward(q);
  nan_position.points[7].position[sim::kBaseX] = std::nan("");
  auto out = sim.execute(nan_position);
  ASSERT_FALSE(out);
  EXPECT_EQ(out.error().message, "trajectory point 7 is not finite");
  Motion nan_time = drive_forward(q);
  nan_time.points[3].time_s = std::nan("");
  out = sim.execute(nan_time);
  ASSERT_FALSE(out);
  EXPECT_EQ(out.error().message, "trajectory point 3 is not finite");
  EXPECT_EQ(sim.time(), before);
  EXPECT_TRUE(sim.execute(drive_forward(q)));
}

// The fidelity is a setting of the run: restoring a checkpoint (made at any
// level) or changing the masses keeps it.
TEST(Fidelity, IsKeptAcrossRestoreAndNewMasses) {
  const sim::JointVector q = home_configuration();
  UnloaderOptions options;
  options.fidelity = sim::Fidelity::kAdaptive;
  UnloaderSimulation full(robot(), block_ahead_of(q, 10.0));
  UnloaderSimulation adaptive(robot(), block_ahead_of(q, 10.0), q, options);
  EXPECT_EQ(full.physics().fidelity(), sim::Fidelity::kFull);
  EXPECT_EQ(adaptive.physics().fidelity(), sim::Fidelity::kAdaptive);
  adaptive.restore(*full.save());
  EXPECT_EQ(adaptive.physics().fidelity(), sim::Fidelity::kAdaptive);
  ASSERT_TRUE(adaptive.set_masses({{1, 5.0}}).has_value());
  EXPECT_EQ(adaptive.physics().fidelity(), sim::Fidelity::kAdaptive);
  adaptive.set_fidelity(sim::Fidelity::kFull);
  EXPECT_EQ(adaptive.physics().fidelity(), sim::Fidelity::kFull);
}

}  // namespace
}  // namespace plr::actions
