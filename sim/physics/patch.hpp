// Internal: contact patches of a box against another box or a plane, by face
// clipping. FCL's box-box contact gives at most 4 culled points that appear
// and vanish as a yawed box rocks, and its normal can switch axis; a penalty
// force built on such points jumps and keeps resting piles jittering. A patch
// here is the overlap of the two faces in contact, cut where the penetration
// depth reaches zero, sampled at its vertices with weights that sum to 1 and
// shrink with a vertex's edges, so forces built on it change continuously
// with the poses.
#pragma once

#include <Eigen/Geometry>
#include <vector>

namespace plr::sim::detail {

struct PatchPoint {
  Eigen::Vector3d p;  // midway between the two surfaces
  double depth;       // >= 0
  double weight;      // share of the patch; all weights sum to 1
};

struct Patch {
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  // unit, points into box a
  std::vector<PatchPoint> points;                    // empty: no contact
};

// Box a (full extents `size_a`, pose `pose_a`) against box b.
void box_box_patch(const Eigen::Vector3d& size_a, const Eigen::Isometry3d& pose_a,
                   const Eigen::Vector3d& size_b, const Eigen::Isometry3d& pose_b, Patch& patch);

// A box against the half-space {x : normal . x <= offset} (outside the
// trailer); `normal` is unit and points into the free side.
void box_plane_patch(const Eigen::Vector3d& size, const Eigen::Isometry3d& pose,
                     const Eigen::Vector3d& normal, double offset, Patch& patch);

}  // namespace plr::sim::detail
