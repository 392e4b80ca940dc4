// FCL collision checking of the unloader against the world W and itself.
//
// World: the trailer shell as an octree (octomap::OcTree -> fcl::OcTree) plus
// every perceived box as an FCL box. The octree counts outside the trailer's
// inner volume (world.trailer) only: inside it the perceived boxes are the
// obstacles, and a shape within it is clear of the shell however the
// octree's grid rounds the walls. Self-collision: every pair of links
// except the URDF-adjacent ones and those allowed with allow_collision().
// Boxes held by the suction plate are attached to the plate link, so they
// collide with the world and with the rest of the robot like part of the arm.
//
// Pairs of boxes are settled by FCL's 15-axis OBB test (exact for boxes), and
// a box against the octree by the same test on a prefix-sum table of
// occupied voxels; cylinders and spheres go on to FCL's narrow phase and
// octree traversal when their enclosing box meets something.
//
// Motion checks are conservative sweeps: each link's shapes, inflated by a
// bound on how far any of their points moves over half a segment, are checked
// at the segment's midpoint; a segment whose sweep touches something is split
// until its sweep is below `motion_resolution`, where the state itself is
// checked. Far from obstacles a whole segment costs one check; near them the
// motion is checked at `motion_resolution` of link travel.
//
// A world's trailer part (the FCL octree object and the occupied-voxel
// table) is a function of the octree alone: checkers on the same octree share
// it, so a checker is cheap to make again on the same trailer, and cheaper to
// keep and give the next world's boxes (set_boxes, set_world).
//
// Not thread-safe: a checker updates its FCL objects in place. Use one per
// thread; checkers on several threads may share a trailer.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "plr/sim/robot_model.hpp"
#include "plr/sim/world.hpp"

namespace octomap {
class OcTree;
}

namespace plr::sim {

struct CollisionOptions {
  // Voxel size (and wall thickness) of the trailer octree built when none is
  // given (plr/sim/octree.hpp).
  double octree_resolution = 0.05;
  // Largest link travel (m) between two checked states of a motion.
  double motion_resolution = 0.02;
  // Joint-limit tolerance of is_valid().
  double limit_tolerance = 1e-9;
};

struct CollisionStats {
  std::uint64_t state_checks = 0;
  std::uint64_t sweep_checks = 0;
};

class CollisionChecker {
 public:
  // `octree` is the world's occupancy; null builds the trailer shell of
  // `world.trailer`. The trailer part is found by the octree's identity (the
  // shared_ptr's owner) or the shell's sizes, and computed again only when
  // no checker holds it and it was not the last one computed; so an octree
  // must not change once a checker is made on it (pass a changed one as a
  // new shared_ptr). The robot model must outlive the checker.
  CollisionChecker(const RobotModel& robot, const World& world,
                   std::shared_ptr<const octomap::OcTree> octree = nullptr,
                   const CollisionOptions& options = {});
  ~CollisionChecker();
  CollisionChecker(CollisionChecker&&) noexcept;
  CollisionChecker& operator=(CollisionChecker&&) noexcept;

  const RobotModel& robot() const;
  const CollisionOptions& options() const;

  // Replaces the world's boxes, answering from then on as a checker built on
  // them would. FCL objects are reused by box id; the trailer and the robot's
  // shapes are kept, and so are held boxes and ignored ids.
  void set_boxes(const std::vector<Box>& boxes);
  // Replaces the world: the trailer part too if `octree` (or, when null, the
  // trailer shell) differs from the checker's, then set_boxes(world.boxes).
  void set_world(const World& world, std::shared_ptr<const octomap::OcTree> octree = nullptr);

  // Trailer tables computed in this process so far (for tests and benchmarks
  // of the sharing).
  static std::uint64_t trailer_builds();
  // Which computation of the trailer part this checker uses: another serial
  // is another trailer (or the same one computed again), the same serial
  // the same trailer part.
  std::uint64_t trailer_serial() const;

  // Links `a` and `b` may touch. Throws std::invalid_argument on an unknown name.
  void allow_collision(const std::string& a, const std::string& b);
  // World boxes left out of the checks (e.g. the box about to be grasped).
  void ignore_box(std::uint32_t id);
  void clear_ignored_boxes();
  // Rigidly attaches `box` to the plate at its current world pose, taken with
  // the robot at `q`; the same box is then ignored as a world obstacle. Its
  // shape is 3 mm smaller on every side: a box just gripped still touches
  // the floor or its neighbours, which the move away from them must not count.
  void attach_box(const Box& box, const JointVector& q);
  void detach_all();

  // Within joint limits and free of world and self collision.
  bool is_valid(const JointVector& q) const;
  // Both ends and the straight joint-space segment between them are valid.
  // With check_endpoints false the caller vouches for both ends.
  bool is_motion_valid(const JointVector& a, const JointVector& b,
                       bool check_endpoints = true) const;
  // What collides at q, e.g. "arm_fore - box 12", "plate - trailer",
  // "arm_1 beyond limits"; empty if q is valid.
  std::string describe_collision(const JointVector& q) const;
  // The first world collision at q of the links no arm joint moves (the
  // base, the nose and its scoop), e.g. "scoop - box 12"; empty if they
  // are clear. The arm and what it holds are left out: where the base can
  // stand whatever the arm does, a planner's cheap necessary condition.
  std::string base_collision(const JointVector& q) const;

  const CollisionStats& stats() const;
  void reset_stats();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace plr::sim
