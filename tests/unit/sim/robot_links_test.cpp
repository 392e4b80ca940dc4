// The robot model's shapes drive the physics: a nose lowered into a box pushes it.
#include <gtest/gtest.h>

#include "plr/sim/robot_links.hpp"

namespace plr::sim {
namespace {

TEST(RobotLinks, ShapesFollowTheModel) {
  const RobotModel model = RobotModel::fromUrdfFile(PLR_UNLOADER_URDF);
  const Config q = Config::Zero();
  const std::vector<LinkGeometry> links = robot_link_geometry(model, q, 0.5);
  std::size_t shapes = 0;
  for (const Link& l : model.links()) shapes += l.shapes.size();
  ASSERT_EQ(links.size(), shapes);
  int belts = 0;
  for (const LinkGeometry& g : links) belts += g.belt_speed > 0.0;
  EXPECT_EQ(belts, 1);
  // The physics plate's normal (+z) is the model's plate normal (+x).
  const SuctionPlate plate = suction_plate_at(model, q);
  EXPECT_TRUE(plate.pose.linear().col(2).isApprox(model.platePose(q).linear().col(0), 1e-12));
  EXPECT_TRUE(plate.pose.translation().isApprox(model.platePose(q).translation(), 1e-12));
}

TEST(RobotLinks, DrivingTheBaseForwardPushesABox) {
  const RobotModel model = RobotModel::fromUrdfFile(PLR_UNLOADER_URDF);
  Config q = Config::Zero();
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

}  // namespace
}  // namespace plr::sim
