// sim/world/geometry.cpp: overlap checks and the perceived world.
#include <gtest/gtest.h>

#include <algorithm>

#include "plr/sim/generators.hpp"

namespace plr::sim {
namespace {

Box cube(std::uint32_t id, const Eigen::Vector3d& centre, double size = 0.4) {
  Box b;
  b.id = id;
  b.size = Eigen::Vector3d::Constant(size);
  b.pose.translation() = centre;
  b.mass = 5.0;
  return b;
}

TEST(Geometry, FindsInterpenetrationAndBoxesOutsideTheTrailer) {
  World w = generate_world(EnvFamily::kA1, 1);
  w.boxes[1].pose.translation() = w.boxes[0].pose.translation() + Eigen::Vector3d(0.05, 0, 0);
  w.boxes[2].pose.translation().z() = -0.1;
  const auto found = find_interpenetrations(w, 1e-3);
  EXPECT_NE(std::find(found.begin(), found.end(), std::make_pair(w.boxes[0].id, w.boxes[1].id)),
            found.end());
  EXPECT_NE(std::find(found.begin(), found.end(), std::make_pair(w.boxes[2].id, w.boxes[2].id)),
            found.end());
}

TEST(Geometry, TouchingIsNotInterpenetratingAndTheToleranceCounts) {
  World w;
  w.boxes = {cube(1, {5.0, 0.0, 0.2}), cube(2, {5.4, 0.0, 0.2})};
  EXPECT_TRUE(find_interpenetrations(w, 1e-6).empty());
  w.boxes[1].pose.translation().x() = 5.398;  // 2 mm into box 1
  EXPECT_TRUE(find_interpenetrations(w, 3e-3).empty());
  EXPECT_EQ(find_interpenetrations(w, 1e-3),
            (std::vector<std::pair<std::uint32_t, std::uint32_t>>{{1, 2}}));
}

TEST(Geometry, RotatedBoxStickingThroughASideWall) {
  World w;
  Box b = cube(7, {8.0, w.trailer.width / 2 - 0.21, 0.2});
  w.boxes = {b};
  EXPECT_TRUE(find_interpenetrations(w, 1e-3).empty());
  // Turned by 45 degrees its corner reaches 0.28 m from its centre.
  w.boxes[0].pose.linear() =
      Eigen::AngleAxisd(M_PI / 4, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  EXPECT_EQ(find_interpenetrations(w, 1e-3),
            (std::vector<std::pair<std::uint32_t, std::uint32_t>>{{7, 7}}));
}

TEST(Geometry, PerceptionDropsMassesOnly) {
  const World truth = generate_world(EnvFamily::kB1, 2);
  const World w = without_masses(truth);
  ASSERT_EQ(w.boxes.size(), truth.boxes.size());
  for (std::size_t i = 0; i < w.boxes.size(); ++i) {
    EXPECT_EQ(w.boxes[i].mass, 0.0);
    EXPECT_EQ(w.boxes[i].id, truth.boxes[i].id);
    EXPECT_TRUE(w.boxes[i].pose.isApprox(truth.boxes[i].pose));
  }
}

}  // namespace
}  // namespace plr::sim
