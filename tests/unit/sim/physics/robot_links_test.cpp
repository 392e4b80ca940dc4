// The robot model's shapes drive the physics: a nose lowered into a box pushes it.
#include <gtest/gtest.h>

#include <algorithm>

#include "plr/sim/robot_links.hpp"

namespace plr::sim {
namespace {

TEST(RobotLinks, ShapesFollowTheModel) {
  const RobotModel model = load_robot().value();
  const JointVector q = JointVector::Zero();
  const std::vector<LinkGeometry> links = robot_link_geometry(model, q, 0.5);
  std::size_t shapes = 0;
  for (const Link& l : model.links()) shapes += l.shapes.size();
  ASSERT_EQ(links.size(), shapes);  // the nose is up: no lip
  int belts = 0, feeders = 0;
  for (const LinkGeometry& g : links) {
    belts += g.belt_speed > 0.0;
    feeders += g.feeds_belt;
  }
  EXPECT_EQ(belts, 3);  // the nose conveyor, the scoop's feeding it, and the body's
  EXPECT_EQ(feeders, 1);
  // The physics plate's normal (+z) is the model's plate normal (+x).
  const SuctionPlate plate = suction_plate_at(model, q);
  EXPECT_TRUE(plate.pose.linear().col(2).isApprox(model.plate_pose(q).linear().col(0), 1e-12));
  EXPECT_TRUE(plate.pose.translation().isApprox(model.plate_pose(q).translation(), 1e-12));
}

TEST(RobotLinks, ThePlateLinkHasTheCupFieldsOutline) {
  // One size for the plate: the URDF's plate link is the suction cups' field
  // (plr/sim/suction_plate.hpp), which the instantiation sizes its plate by.
  const RobotModel model = load_robot().value();
  const int plate = model.link_index("plate");
  ASSERT_GE(plate, 0);
  const auto& shapes = model.links()[static_cast<std::size_t>(plate)].shapes;
  ASSERT_EQ(shapes.size(), 1u);
  ASSERT_EQ(shapes[0].type, CollisionShape::Type::kBox);
  const SuctionPlate cups;
  EXPECT_NEAR(shapes[0].size.y(), cups.extent.y(), 1e-9);  // across
  EXPECT_NEAR(shapes[0].size.z(), cups.extent.x(), 1e-9);  // up
}

TEST(RobotLinks, DrivingTheBaseForwardPushesABox) {
  const RobotModel model = load_robot().value();
  JointVector q = JointVector::Zero();
  q[kBaseX] = 1.0;
  // A box just in front of everything the robot has at this configuration.
  double front = -1e9;
  for (const LinkGeometry& g : robot_link_geometry(model, q)) {
    const Eigen::Vector3d e = g.pose.linear().cwiseAbs() * (0.5 * g.size);
    if (g.pose.translation().z() - e.z() < 0.3)
      front = std::max(front, g.pose.translation().x() + e.x());
  }
  World w;
  Box b;
  b.id = 1;
  b.size = {0.4, 0.4, 0.4};
  b.mass = 5.0;
  b.pose.translation() = Eigen::Vector3d(front + 0.25, 0.0, 0.2);
  w.boxes.push_back(b);
  Simulation sim(w);
  sim.set_robot_links(robot_link_geometry(model, q));
  for (int k = 1; k <= 100; ++k) {
    q[kBaseX] = 1.0 + 0.005 * k;
    sim.set_robot_links(robot_link_geometry(model, q));
    sim.step(0.01);
  }
  EXPECT_GT(sim.world().boxes[0].pose.translation().x(), front + 0.25 + 0.3);
}

World box_on_floor(double x, double y, const Eigen::Vector3d& size, double mass) {
  World w;
  Box b;
  b.id = 1;
  b.size = size;
  b.mass = mass;
  b.pose.translation() = Eigen::Vector3d(x, y, 0.5 * size.z());
  w.boxes.push_back(b);
  return w;
}

// The sweep: nose pitched down until the scoop's blade meets the floor, scoop
// out, belts running, base driven forward at 0.3 m/s.
JointVector sweep_pose(double base_x) {
  JointVector q = JointVector::Zero();
  q[kBaseX] = base_x;
  q[kArm2] = -1.0;  // arm folded over the base
  q[kArm3] = 2.0;
  q[kNose2] = 0.05;
  q[kNose3] = 0.3;
  return q;
}

TEST(RobotLinks, TheScoopGetsUnderABoxAndItsBeltsCarryItOut) {
  const RobotModel model = load_robot().value();
  // A box near the side wall's lane, 0.1 m ahead of the blade.
  JointVector q = sweep_pose(1.0);
  const auto shapes = robot_link_geometry(model, q, 1.0);
  const auto feeders = std::count_if(shapes.begin(), shapes.end(),
                                     [](const LinkGeometry& g) { return g.feeds_belt; });
  ASSERT_EQ(feeders, 2);  // the scoop, and its lip
  const auto lip = std::find_if(shapes.rbegin(), shapes.rend(),
                                [](const LinkGeometry& g) { return g.feeds_belt; });
  const double lowest =
      lip->pose.translation().z() - (lip->pose.linear().cwiseAbs() * (0.5 * lip->size)).z();
  EXPECT_LT(lowest, 0.0);
  EXPECT_GT(lowest, -0.01);
  Simulation sim(box_on_floor(1.0 + 1.3 + 0.1 + 0.2, 0.8, {0.4, 0.4, 0.3}, 8.0));
  ASSERT_GE(sim.settle(1.0), 0.0);
  for (int k = 1; k <= 200 && sim.unloaded().empty(); ++k) {
    q[kBaseX] = std::min(2.0, q[kBaseX] + 0.3 * 0.01);
    sim.set_robot_links(robot_link_geometry(model, q, 1.0));
    sim.step(0.01);
  }
  for (int k = 0; k < 600 && sim.unloaded().empty(); ++k) sim.step(0.01);
  ASSERT_EQ(sim.unloaded().size(), 1u);
  EXPECT_EQ(sim.unloaded()[0].box_id, 1u);
}

// A belt whose surface lies level with the floor (as a raised nose's does,
// extended behind its end): a box on the floor 1 m behind the end lies in
// the belt's plane but not on it, and is not unloaded; one on the belt at
// its end is.
TEST(RobotLinks, ABoxBehindABeltsEndIsNotUnloaded) {
  LinkGeometry belt;
  belt.size = {2.0, 1.0, 0.05};
  belt.pose.translation() = Eigen::Vector3d(5.0, 0.0, -0.025);
  belt.belt_speed = 0.5;
  Simulation behind(box_on_floor(3.0, 0.0, {0.4, 0.4, 0.3}, 8.0));
  behind.set_robot_links({belt});
  behind.step(0.1);
  EXPECT_TRUE(behind.unloaded().empty());
  Simulation at_end(box_on_floor(4.2, 0.0, {0.4, 0.4, 0.3}, 8.0));
  at_end.set_robot_links({belt});
  at_end.step(0.1);
  EXPECT_EQ(at_end.unloaded().size(), 1u);
}

}  // namespace
}  // namespace plr::sim
