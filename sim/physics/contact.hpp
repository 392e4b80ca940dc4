// Internal: penalty contact between boxes, the trailer and robot shapes.
// Box-box and box-robot contact points come from FCL; box-trailer contact
// from the box corners below each trailer plane.
#pragma once

#include <fcl/fcl.h>

#include <memory>
#include <vector>

#include "state.hpp"

namespace plr::sim::detail {

class Contacts {
 public:
  Contacts(const PhysicsOptions& options, const Trailer& trailer);

  // Geometry cache; call when boxes or robot shapes change.
  void set_boxes(const std::vector<Body>& bodies);
  void set_links(const std::vector<LinkGeometry>& links);

  // Wrenches on every body for the step starting now (awake: what moves it;
  // held: what the cups must resist in addition to weight). Updates the
  // friction springs in `state.pairs` and lists sleeping boxes that something
  // moving touches in `wake`.
  void compute(State& state, const std::vector<Mover>& links, double dt,
               std::vector<Wrench>& wrenches, std::vector<int>& wake);

 private:
  struct Point {
    Eigen::Vector3d p, n;  // n points into body a
    double depth;
  };
  struct Other {
    double mass;  // 0 for the trailer and robot shapes (immovable)
    Eigen::Vector3d centre, v, w, belt;
  };
  void apply(State& state, int a, int b, const Other& other, const PairKey& key, double mu,
             double dt, std::vector<Wrench>& wrenches);
  bool collide(const fcl::CollisionGeometryd& ga, const Eigen::Isometry3d& pa,
               const fcl::CollisionGeometryd& gb, const Eigen::Isometry3d& pb);

  PhysicsOptions options_;
  Trailer trailer_;
  std::vector<fcl::Boxd> box_shapes_;
  std::vector<std::unique_ptr<fcl::CollisionGeometryd>> link_shapes_;
  std::vector<Eigen::Vector3d> link_half_;  // bounding half extents in the link frame
  std::vector<Eigen::Vector3d> lo_, hi_;    // world AABBs of the bodies this step
  std::vector<Point> points_;
  std::vector<PairState> old_pairs_;
  fcl::CollisionRequestd request_;
};

}  // namespace plr::sim::detail
