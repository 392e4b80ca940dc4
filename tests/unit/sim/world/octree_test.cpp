#include <gtest/gtest.h>

#include "plr/sim/octree.hpp"

namespace plr::sim {
namespace {

bool occupied(const octomap::OcTree& t, double x, double y, double z) {
  const octomap::OcTreeNode* n =
      t.search(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z));
  return n != nullptr && t.isNodeOccupied(n);
}

TEST(Octree, TrailerShellIsOccupiedInsideAndRearAreNot) {
  const Trailer t;
  const auto tree = build_trailer_octree(t, {0.1, 0.1});
  EXPECT_DOUBLE_EQ(tree->getResolution(), 0.1);
  EXPECT_TRUE(occupied(*tree, 8.0, 0.0, -0.05));    // floor
  EXPECT_TRUE(occupied(*tree, 8.0, 0.0, 2.75));     // ceiling
  EXPECT_TRUE(occupied(*tree, 8.0, -1.3, 1.0));     // left wall
  EXPECT_TRUE(occupied(*tree, 8.0, 1.3, 1.0));      // right wall
  EXPECT_TRUE(occupied(*tree, 16.05, 0.0, 1.0));    // front wall
  EXPECT_FALSE(occupied(*tree, 8.0, 0.0, 1.0));     // inside
  EXPECT_FALSE(occupied(*tree, -0.05, 0.0, 1.0));   // open rear
  EXPECT_FALSE(occupied(*tree, 15.85, 1.1, 2.55));  // inner corner
  // The floor goes on behind the open rear, where the robot drives in.
  EXPECT_TRUE(occupied(*tree, -4.0, 0.0, -0.05));
  EXPECT_FALSE(occupied(*tree, -4.0, 0.0, 2.75));  // no ceiling there
  const auto bare = build_trailer_octree(t, {.resolution = 0.1, .floor_behind = 0.0});
  EXPECT_FALSE(occupied(*bare, -0.5, 0.0, -0.05));
}

TEST(Octree, BoxesCanBeAdded) {
  const Trailer t;
  auto tree = build_trailer_octree(t, {0.05, 0.05});
  Box b;
  b.size = {0.4, 0.3, 0.2};
  b.pose.translation() = Eigen::Vector3d(10.0, 0.0, 0.1);
  b.pose.linear() = Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  EXPECT_FALSE(occupied(*tree, 10.0, 0.0, 0.1));
  add_boxes_to_octree(*tree, {b});
  EXPECT_TRUE(occupied(*tree, 10.0, 0.0, 0.1));
  EXPECT_TRUE(occupied(*tree, 10.0 + 0.17 * std::cos(0.5), 0.17 * std::sin(0.5), 0.1));
  EXPECT_FALSE(occupied(*tree, 10.0, 0.0, 0.35));
}

TEST(Octree, RejectsBadResolution) {
  EXPECT_DEATH(build_trailer_octree(Trailer{}, {0.0, 0.05}), "resolution 0");
}

}  // namespace
}  // namespace plr::sim
