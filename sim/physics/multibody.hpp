// Internal: the Simbody system of the awake boxes. Rebuilt whenever the set
// of awake boxes changes; Simbody types stay in multibody.cpp.
#pragma once

#include <Eigen/Geometry>
#include <memory>
#include <vector>

namespace plr::sim::detail {

struct FreeBody {
  double mass = 1.0;
  Eigen::Vector3d size{0.4, 0.4, 0.4};
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  Eigen::Vector3d v = Eigen::Vector3d::Zero(), w = Eigen::Vector3d::Zero();
  // Coordinates to carry over exactly (7 q: quaternion wxyz + position, 6 u),
  // empty to fit them to pose and velocity.
  std::vector<double> q, u;
};

class Multibody {
 public:
  Multibody();
  ~Multibody();
  Multibody(const Multibody&) = delete;
  Multibody& operator=(const Multibody&) = delete;

  void build(const std::vector<FreeBody>& bodies, double gravity, double time);
  int size() const;
  // Body i's coordinates (see FreeBody::q, u).
  void coordinates(int i, std::vector<double>& q, std::vector<double>& u) const;
  void read(int i, Eigen::Isometry3d& pose, Eigen::Vector3d& v, Eigen::Vector3d& w) const;
  // Force and torque (about the centre, world frame) for the next step.
  void set_wrench(int i, const Eigen::Vector3d& force, const Eigen::Vector3d& torque);
  // A velocity change (world frame, at the centre) for body i, added by the
  // next step along with its forces' (impulses computed outside Simbody).
  void add_velocity(int i, const Eigen::Vector3d& dv, const Eigen::Vector3d& dw);
  // One semi-explicit Euler step: u += kick + dt * udot(q, u); q += dt * N(q) u.
  void step(double dt);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace plr::sim::detail
