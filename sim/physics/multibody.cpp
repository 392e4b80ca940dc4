// The only translation unit that includes Simbody. No `using namespace
// SimTK`: its generic operators would capture Eigen expressions.
#include "multibody.hpp"

#include <Simbody.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace plr::sim::detail {
namespace {

SimTK::Vec3 to_simtk(const Eigen::Vector3d& v) {
  return SimTK::Vec3(v.x(), v.y(), v.z());
}
Eigen::Vector3d to_eigen(const SimTK::Vec3& v) {
  return Eigen::Vector3d(v[0], v[1], v[2]);
}

}  // namespace

// The boxes are free bodies without constraints: their accelerations come
// from the tree's O(n) forward dynamics with the forces applied directly
// (weight and the contact wrenches computed outside Simbody), not from a
// force subsystem and the constrained system's solve, which cost most of a
// step for nothing.
struct Multibody::Impl {
  std::unique_ptr<SimTK::MultibodySystem> system;
  SimTK::SimbodyMatterSubsystem* matter = nullptr;
  std::unique_ptr<SimTK::SimbodyMatterSubsystem> matter_owner;
  std::vector<SimTK::MobilizedBody::Free> bodies;
  std::vector<SimTK::MobilizedBodyIndex> index;
  std::vector<SimTK::SpatialVec> weight;          // per body
  SimTK::Vector_<SimTK::SpatialVec> body_forces;  // per Simbody body, Ground first
  SimTK::Vector mobility_forces;                  // none
  SimTK::Vector udot;
  SimTK::Vector_<SimTK::SpatialVec> body_accelerations;
  SimTK::State state;
  SimTK::Vector qdot;
  // Each body's first q and u in the state's coordinates.
  std::vector<int> q0, u0;
  std::vector<double> u_next;
  std::vector<double> kick;  // velocity changes for the next step
  bool kicked = false;       // kick holds something other than zeros
};

namespace {

// The state's coordinates are Simbody vectors; the step works on their
// storage directly (SimTK's vector expressions allocate a temporary per
// operator and index through a helper).
const double* data(const SimTK::Vector& v) {
  return v.getContiguousScalarData();
}
double* data(SimTK::Vector& v) {
  return v.updContiguousScalarData();
}

}  // namespace

Multibody::Multibody() : impl_(std::make_unique<Impl>()) {}
Multibody::~Multibody() = default;

void Multibody::build(const std::vector<FreeBody>& bodies, double gravity, double time) {
  auto next = std::make_unique<Impl>();
  Impl& m = *next;
  m.system = std::make_unique<SimTK::MultibodySystem>();
  m.matter_owner = std::make_unique<SimTK::SimbodyMatterSubsystem>(*m.system);
  m.matter = m.matter_owner.get();
  for (const FreeBody& b : bodies) {
    const SimTK::Vec3 half = to_simtk(0.5 * b.size);
    SimTK::Body::Rigid body(SimTK::MassProperties(
        b.mass, SimTK::Vec3(0), SimTK::UnitInertia::brick(half[0], half[1], half[2])));
    m.bodies.emplace_back(m.matter->Ground(), SimTK::Transform(), body, SimTK::Transform());
    m.index.push_back(m.bodies.back().getMobilizedBodyIndex());
    m.weight.emplace_back(SimTK::Vec3(0), SimTK::Vec3(0, 0, -gravity * b.mass));
  }
  m.state = m.system->realizeTopology();
  m.system->realizeModel(m.state);
  m.state.setTime(time);
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    const FreeBody& b = bodies[i];
    const SimTK::MobilizedBody::Free& mb = m.bodies[i];
    if (b.q.size() == 7 && b.u.size() == 6) {
      const int q0 = mb.getFirstQIndex(m.state), u0 = mb.getFirstUIndex(m.state);
      for (int k = 0; k < 7; ++k) m.state.updQ()[q0 + k] = b.q[static_cast<std::size_t>(k)];
      for (int k = 0; k < 6; ++k) m.state.updU()[u0 + k] = b.u[static_cast<std::size_t>(k)];
    } else {
      const Eigen::Matrix3d r = b.pose.linear();
      SimTK::Mat33 rm;
      for (int row = 0; row < 3; ++row) {
        for (int col = 0; col < 3; ++col) rm(row, col) = r(row, col);
      }
      mb.setQToFitTransform(
          m.state, SimTK::Transform(SimTK::Rotation(rm, true), to_simtk(b.pose.translation())));
      mb.setUToFitVelocity(m.state, SimTK::SpatialVec(to_simtk(b.w), to_simtk(b.v)));
    }
  }
  m.system->realize(m.state, SimTK::Stage::Velocity);
  if (!m.state.getQ().hasContiguousData() || !m.state.getU().hasContiguousData())
    throw std::logic_error("Multibody: Simbody's q and u are not contiguous");
  for (const auto& mb : m.bodies) {
    m.q0.push_back(mb.getFirstQIndex(m.state));
    m.u0.push_back(mb.getFirstUIndex(m.state));
  }
  m.body_forces.resize(m.matter->getNumBodies());
  m.body_forces.setToZero();
  for (std::size_t i = 0; i < m.index.size(); ++i) m.body_forces[m.index[i]] = m.weight[i];
  m.mobility_forces.resize(m.state.getNU());
  m.mobility_forces.setToZero();
  m.u_next.resize(static_cast<std::size_t>(m.state.getNU()));
  m.kick.assign(static_cast<std::size_t>(m.state.getNU()), 0.0);
  impl_ = std::move(next);
}

int Multibody::size() const {
  return static_cast<int>(impl_->bodies.size());
}

void Multibody::coordinates(int i, std::vector<double>& q, std::vector<double>& u) const {
  const auto& mb = impl_->bodies[static_cast<std::size_t>(i)];
  const int q0 = mb.getFirstQIndex(impl_->state), u0 = mb.getFirstUIndex(impl_->state);
  q.resize(7);
  u.resize(6);
  for (int k = 0; k < 7; ++k) q[static_cast<std::size_t>(k)] = impl_->state.getQ()[q0 + k];
  for (int k = 0; k < 6; ++k) u[static_cast<std::size_t>(k)] = impl_->state.getU()[u0 + k];
}

void Multibody::read(int i, Eigen::Isometry3d& pose, Eigen::Vector3d& v, Eigen::Vector3d& w) const {
  const auto& mb = impl_->bodies[static_cast<std::size_t>(i)];
  const SimTK::Transform& x = mb.getBodyTransform(impl_->state);
  const SimTK::SpatialVec& vel = mb.getBodyVelocity(impl_->state);
  pose = Eigen::Isometry3d::Identity();
  for (int row = 0; row < 3; ++row) {
    for (int col = 0; col < 3; ++col) pose.linear()(row, col) = x.R().asMat33()(row, col);
  }
  pose.translation() = to_eigen(x.p());
  w = to_eigen(vel[0]);
  v = to_eigen(vel[1]);
}

void Multibody::set_wrench(int i, const Eigen::Vector3d& force, const Eigen::Vector3d& torque) {
  Impl& m = *impl_;
  const auto k = static_cast<std::size_t>(i);
  m.body_forces[m.index[k]] = m.weight[k] + SimTK::SpatialVec(to_simtk(torque), to_simtk(force));
}

void Multibody::add_velocity(int i, const Eigen::Vector3d& dv, const Eigen::Vector3d& dw) {
  // A free mobilizer's u is (angular, linear) velocity in the ground frame.
  Impl& m = *impl_;
  const auto u0 = static_cast<std::size_t>(m.u0[static_cast<std::size_t>(i)]);
  for (int k = 0; k < 3; ++k) {
    m.kick[u0 + static_cast<std::size_t>(k)] += dw[k];
    m.kick[u0 + 3 + static_cast<std::size_t>(k)] += dv[k];
  }
  m.kicked = true;
}

void Multibody::step(double dt) {
  Impl& m = *impl_;
  SimTK::State& s = m.state;
  m.system->realize(s, SimTK::Stage::Dynamics);
  m.matter->calcAccelerationIgnoringConstraints(s, m.mobility_forces, m.body_forces, m.udot,
                                                m.body_accelerations);
  // Adding the kick here rather than to the state keeps the state realized
  // to Velocity between steps (no second velocity realization per step).
  const std::size_t nu = m.u_next.size();
  {
    const double* u = data(s.getU());
    const double* udot = data(m.udot);
    for (std::size_t i = 0; i < nu; ++i) m.u_next[i] = u[i] + m.kick[i] + dt * udot[i];
  }
  if (m.kicked) {
    std::fill(m.kick.begin(), m.kick.end(), 0.0);
    m.kicked = false;
  }
  std::copy(m.u_next.begin(), m.u_next.end(), data(s.updU()));
  m.matter->multiplyByN(s, false, s.getU(), m.qdot);
  double* q = data(s.updQ());
  const double* qdot = data(m.qdot);
  const auto nq = static_cast<std::size_t>(s.getNQ());
  for (std::size_t i = 0; i < nq; ++i) q[i] += dt * qdot[i];
  // Free mobilizers use quaternions (first 4 q); keep them unit length.
  for (const int q0 : m.q0) {
    double* quat = q + q0;
    double n = 0.0;
    for (int k = 0; k < 4; ++k) n += quat[k] * quat[k];
    n = 1.0 / std::sqrt(n);
    for (int k = 0; k < 4; ++k) quat[k] *= n;
  }
  s.updTime() += dt;
  m.system->realize(s, SimTK::Stage::Velocity);
}

}  // namespace plr::sim::detail
