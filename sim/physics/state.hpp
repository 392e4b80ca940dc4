// Internal: the plain (Simbody-free) state of a simulation. Everything a
// snapshot must hold lives here, so copying it is the snapshot.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <optional>
#include <tuple>
#include <vector>

#include "plr/sim/physics.hpp"

namespace plr::sim::detail {

enum class Mode : std::uint8_t { kAwake, kAsleep, kHeld, kGone };

struct Body {
  Box box;  // pose is the current pose; box centre = body origin
  Eigen::Vector3d v = Eigen::Vector3d::Zero();  // world frame, at the centre
  Eigen::Vector3d w = Eigen::Vector3d::Zero();
  Mode mode = Mode::kAwake;
  double still = 0.0;                                      // s spent slow enough to sleep
  Eigen::Isometry3d rest = Eigen::Isometry3d::Identity();  // pose when `still` began
  double radius = 0.0;                                     // half diagonal
  // While held: pose relative to the suction plate, what the cups hold.
  Eigen::Isometry3d grip = Eigen::Isometry3d::Identity();
  double capacity = 0.0;
  double load = 0.0;  // low-pass filtered
};

// A contact pair's tangential spring (static friction that does not creep).
struct PairKey {
  std::uint32_t a = 0, b = 0;
  std::uint8_t kind = 0;  // 0 box-box, 1 box-robot shape, 2 box-trailer plane
  friend bool operator<(const PairKey& x, const PairKey& y) {
    return std::tie(x.a, x.b, x.kind) < std::tie(y.a, y.b, y.kind);
  }
  friend bool operator==(const PairKey& x, const PairKey& y) {
    return x.a == y.a && x.b == y.b && x.kind == y.kind;
  }
};
struct PairState {
  PairKey key;
  Eigen::Vector3d bristle = Eigen::Vector3d::Zero();  // tangential spring stretch (m)
  double twist = 0.0;  // torsional spring about the contact normal (rad)
};

struct State {
  double time = 0.0;
  std::vector<Body> bodies;
  std::vector<PairState> pairs;  // sorted by key
  std::vector<LinkGeometry> links, link_targets;
  std::optional<SuctionPlate> plate, plate_target;
  Eigen::Vector3d plate_velocity = Eigen::Vector3d::Zero();  // over the last step() call
  std::vector<UnloadEvent> unloaded;
  std::vector<SuctionEvent> suction_events;
  std::vector<BeltLoad> belts;                  // by drive id; speed_fraction is the drive's state
  std::vector<RobotContactForce> robot_forces;  // of the last step() call
  // Only filled inside snapshots: the bodies Simbody integrates and their
  // exact coordinates, so a restored run repeats the original bit for bit.
  std::vector<int> slots;
  std::vector<double> q, u;
  bool rebuild = true;
};

}  // namespace plr::sim::detail

namespace plr::sim {

struct Snapshot::Data {
  Trailer trailer;
  PhysicsOptions options;
  detail::State state;
};

}  // namespace plr::sim

namespace plr::sim::detail {

// A robot shape or held box as it moves during one fixed step.
struct Mover {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  Eigen::Vector3d v = Eigen::Vector3d::Zero(), w = Eigen::Vector3d::Zero();
  Eigen::Vector3d belt = Eigen::Vector3d::Zero();  // surface velocity of a belt
  // Unit direction of a belt that is switched on (zero otherwise), even
  // while its drive stalls: the load on it is still felt.
  Eigen::Vector3d belt_dir = Eigen::Vector3d::Zero();
  double speed = 0.0;  // fastest point speed (m/s)
};

struct Wrench {
  Eigen::Vector3d force = Eigen::Vector3d::Zero();
  Eigen::Vector3d torque = Eigen::Vector3d::Zero();  // about the box centre
};

// A fixed step's wrenches, one per body, zero before its contacts: only the
// moving (awake and held) bodies' entries are written and read, so only
// those are cleared (a wall's sleeping boxes cost nothing).
inline void clear_wrenches(std::vector<Wrench>& wrenches, std::size_t bodies,
                           const std::vector<int>& moving) {
  wrenches.resize(bodies);
  for (const int i : moving) wrenches[static_cast<std::size_t>(i)] = Wrench{};
}

}  // namespace plr::sim::detail
