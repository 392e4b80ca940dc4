// Internal: penalty contact between boxes, the trailer and robot shapes.
// Box-box and box-trailer contact are face-clipped patches (patch.hpp);
// box-robot contact points come from FCL (robot shapes include cylinders).
#pragma once

#include <fcl/fcl.h>

#include <memory>
#include <vector>

#include "broad_phase.hpp"
#include "patch.hpp"
#include "state.hpp"

namespace plr::sim::detail {

class Contacts {
 public:
  Contacts(const PhysicsOptions& options, const Trailer& trailer);

  // Geometry cache; call when boxes or robot shapes change.
  void set_boxes(const std::vector<Body>& bodies);
  void set_links(const std::vector<LinkGeometry>& links);
  // A box was removed (the broad phase then looks at every box once).
  void box_removed() { broad_.mark_stale(); }

  // Before the fixed steps of a Simulation::step() call: each robot shape's
  // centre moves on a line from `from` to `to` during the call. Finds once
  // the boxes each shape may reach in the call, so that compute() tests
  // only those and the boxes moving in the call (a sleeping box does not
  // move), not the grid cells around the shape at every step.
  void sweep_links(const std::vector<Body>& bodies, const std::vector<Eigen::Vector3d>& from,
                   const std::vector<Eigen::Vector3d>& to);

  // Wrenches on every body for the step starting now (awake: what moves it;
  // held: what the cups must resist in addition to weight). Updates the
  // friction springs in `state.pairs` and lists sleeping boxes that something
  // moving touches in `wake`. `moving`: the awake and held bodies,
  // ascending (the sleeping ones are only found through the broad phase).
  // `active` (adaptive fidelity; null at full): per body, whether it has a
  // contact path to the action; such a box wakes the sleeping boxes within
  // the wake margin as soon as it moves at sleep_speed, not wake_speed.
  void compute(State& state, const std::vector<int>& moving, const std::vector<Mover>& links,
               double dt, std::vector<Wrench>& wrenches, std::vector<int>& wake,
               const std::vector<std::uint8_t>* active = nullptr);
  // Fast fidelity. The broad phase brought up to date with the bodies
  // (`moving`: as for compute()), to query before compute() runs.
  void update_broad_phase(const std::vector<Body>& bodies, const std::vector<int>& moving) {
    broad_.update(bodies, moving);
  }
  const BroadPhase& broad_phase() const { return broad_; }
  // Into `wake`: the sleeping boxes that a robot shape at its pose in
  // `links` presses into deeper than wake_depth while it moves, or that lie
  // on its running belt (the belt carries them), and those a held box at
  // `held_poses[k]` (body `held[k]`) presses into deeper than wake_depth.
  // A lighter touch leaves a box where it is: it is not pushed.
  void pressed(const State& state, const std::vector<Mover>& links, const std::vector<int>& held,
               const std::vector<Eigen::Isometry3d>& held_poses, std::vector<int>& wake);
  // Compute() at fast fidelity: a moving robot shape wakes a sleeping box
  // only as pressed() does, and a held box wakes none by coming near.
  void set_fast(bool fast) { fast_ = fast; }

  // From the last compute(), per robot shape: the force the boxes exert on
  // it (world frame), and the force its belt exerts on them along belt_dir.
  const std::vector<Eigen::Vector3d>& link_forces() const { return link_force_; }
  const std::vector<double>& belt_forces() const { return belt_force_; }

  // Damping of the box-box and box-trailer contacts found by the last
  // compute(): applied to the awake boxes' velocities before the step, as
  // impulses that let each damper's relative speed decay exactly over dt
  // (Gauss-Seidel, one pass over the pairs' points and friction patches).
  // Explicit damping is only stable while dt * c / m stays small, which
  // leaves a stack of boxes rocking on its contact springs for seconds; this
  // is stable at any c, so boxes are damped like cardboard (no bounce).
  // Impulses on held boxes go to their wrenches, for the suction load.
  // `moving` as for compute().
  void damp(State& state, const std::vector<int>& moving, double dt, std::vector<Wrench>& wrenches);

 private:
  struct Point {
    Eigen::Vector3d p, n;  // n points into body a
    double depth;
    double weight;  // share of the pair's stiffness; a pair's weights sum to 1
  };
  struct Other {
    double mass;  // 0 for the trailer and robot shapes (immovable)
    Eigen::Vector3d centre, v, w, belt, belt_dir;
  };
  struct Damper {
    int a, b;  // b < 0: the trailer or a sleeping box; a held b moves but takes no impulse
    Eigen::Vector3d p, n;
    double c;      // N s/m
    double limit;  // largest impulse against the motion (normal: the spring's this step)
    bool tangential;
  };
  void apply(State& state, int a, int b, const Other& other, const PairKey& key, double mu,
             double dt, std::vector<Wrench>& wrenches);
  bool collide(const fcl::CollisionGeometryd& ga, const Eigen::Isometry3d& pa,
               const fcl::CollisionGeometryd& gb, const Eigen::Isometry3d& pb);
  bool take(const Patch& patch);  // into points_; false if empty
  // Whether the last collide()'s box lies on the shape's running belt, which
  // carries it: fast fidelity wakes it for that.
  bool on_belt(const Mover& link) const;

  PhysicsOptions options_;
  Trailer trailer_;
  std::vector<fcl::Boxd> box_shapes_;
  std::vector<std::unique_ptr<fcl::CollisionGeometryd>> link_shapes_;
  std::vector<Eigen::Vector3d> link_half_;  // bounding half extents in the link frame
  BroadPhase broad_;
  std::vector<int> near_;  // a query's answer
  // From sweep_links(): per robot shape, the boxes it may reach in the
  // call; the bodies awake or held at any step of the call so far; scratch.
  std::vector<std::vector<int>> link_reach_;
  std::vector<int> moved_, merged_;
  std::vector<Point> points_;
  Patch patch_;
  std::vector<PairState> old_pairs_;
  std::vector<Damper> dampers_;
  std::vector<Eigen::Matrix3d> inverse_inertia_;
  std::vector<Eigen::Vector3d> link_force_;
  std::vector<double> belt_force_;
  fcl::CollisionRequestd request_;
  bool fast_ = false;
};

}  // namespace plr::sim::detail
