#include "plr/sim/octree.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace plr::sim {
namespace {

// Marks every leaf that overlaps the axis-aligned block [lo, hi]. Leaves sit
// on a grid of the resolution, so an unaligned wall is rounded outwards
// (conservative for collision checks).
void fill_block(octomap::OcTree& tree, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  const double r = tree.getResolution();
  const Eigen::Vector3i first = (lo / r).array().floor().cast<int>();
  const Eigen::Vector3i last = ((hi / r).array() - 1e-9).ceil().cast<int>();
  for (int i = first.x(); i < last.x(); ++i) {
    for (int j = first.y(); j < last.y(); ++j) {
      for (int k = first.z(); k < last.z(); ++k) {
        tree.updateNode(
            octomap::point3d(static_cast<float>((i + 0.5) * r), static_cast<float>((j + 0.5) * r),
                             static_cast<float>((k + 0.5) * r)),
            true, true);
      }
    }
  }
}

}  // namespace

std::unique_ptr<octomap::OcTree> build_trailer_octree(const Trailer& t,
                                                      const OctreeOptions& options) {
  if (!(options.resolution > 0.0) || !(options.wall_thickness > 0.0) ||
      !(options.floor_behind >= 0.0)) {
    std::fprintf(stderr,
                 "build_trailer_octree: resolution %g, wall thickness %g, floor behind %g\n",
                 options.resolution, options.wall_thickness, options.floor_behind);
    std::abort();  // a caller's bug: parameters are checked where they are read
  }
  auto tree = std::make_unique<octomap::OcTree>(options.resolution);
  const double th = std::max(options.wall_thickness, options.resolution);
  const double w = 0.5 * t.width;
  // Side walls and ceiling span the full depth; the front wall closes
  // x = depth; the floor goes on behind the open rear, where the robot drives.
  fill_block(*tree, {-options.floor_behind, -w - th, -th}, {t.depth + th, w + th, 0.0});  // floor
  fill_block(*tree, {0.0, -w - th, t.height}, {t.depth + th, w + th, t.height + th});     // ceiling
  fill_block(*tree, {0.0, -w - th, 0.0}, {t.depth + th, -w, t.height});                   // left
  fill_block(*tree, {0.0, w, 0.0}, {t.depth + th, w + th, t.height});                     // right
  fill_block(*tree, {t.depth, -w, 0.0}, {t.depth + th, w, t.height});                     // front
  tree->updateInnerOccupancy();
  return tree;
}

void add_boxes_to_octree(octomap::OcTree& tree, const std::vector<Box>& boxes) {
  // Samples at half the leaf size so a rotated box leaves no leaf out.
  const double r = 0.5 * tree.getResolution();
  for (const Box& box : boxes) {
    const Eigen::Vector3d half = 0.5 * box.size;
    const Eigen::Vector3i n = (box.size / r).array().ceil().cast<int>();
    for (int i = 0; i < n.x(); ++i) {
      for (int j = 0; j < n.y(); ++j) {
        for (int k = 0; k < n.z(); ++k) {
          const Eigen::Vector3d local =
              Eigen::Vector3d((i + 0.5) * r, (j + 0.5) * r, (k + 0.5) * r) - half;
          const Eigen::Vector3d p = box.pose * local.cwiseMin(half);
          tree.updateNode(octomap::point3d(static_cast<float>(p.x()), static_cast<float>(p.y()),
                                           static_cast<float>(p.z())),
                          true, true);
        }
      }
    }
  }
  tree.updateInnerOccupancy();
}

}  // namespace plr::sim
