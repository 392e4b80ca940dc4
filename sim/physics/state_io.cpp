// Snapshot <-> FlatBuffers bytes (sdk/schemas/sim_state.fbs). Every double
// is copied as it is, so a simulation built from the bytes continues the
// original bit for bit. Reading treats the bytes as hostile: the verifier
// checks the layout, then every field is bounded and checked before a
// simulation can step on it (a NaN pose, a zero quaternion or a link count
// that disagrees with its targets would crash or poison a run).
#include <flatbuffers/flatbuffers.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <unordered_set>

#include "plr/msg/sim_state_generated.h"
#include "plr/sim/physics.hpp"
#include "plr/sim/unaligned.hpp"
#include "state.hpp"

namespace plr::sim {

namespace {

namespace msg = plr::msg;
using detail::Body;
using detail::Mode;
using detail::PairKey;
using detail::PairState;
using detail::State;

// Bounds on what a state may hold: far beyond any trailer, small enough that
// a hostile count cannot make us allocate or loop without end.
constexpr std::size_t kMaxBytes = std::size_t{1} << 28;
constexpr std::size_t kMaxBodies = 10000;
constexpr std::size_t kMaxPairs = 40 * kMaxBodies;
constexpr std::size_t kMaxLinks = 1000;
constexpr std::size_t kMaxSuctionEvents = 1000000;
constexpr int kMaxCups = 100;       // per side of the cup grid
constexpr double kMaxLength = 1e3;  // m; sizes, trailer, positions
constexpr double kMaxMass = 1e5;    // kg
// Smallest box side and mass: a denormal one made accelerations infinite and
// Simbody's inertias NaN (found by fuzzing the state bytes).
constexpr double kMinLength = 1e-3;  // m
constexpr double kMinMass = 1e-3;    // kg
constexpr double kMaxSpeed = 1e3;    // m/s and rad/s
constexpr double kUnit = 1e-6;       // rotations orthonormal and quaternions unit within this

msg::Vec3 to_msg(const Eigen::Vector3d& v) {
  return msg::Vec3(v.x(), v.y(), v.z());
}
Eigen::Vector3d from_msg(const msg::Vec3& v) {
  return Eigen::Vector3d(v.x(), v.y(), v.z());
}
msg::SimTransform to_msg(const Eigen::Isometry3d& x) {
  const Eigen::Matrix3d r = x.linear();
  return msg::SimTransform(msg::SimMat3(to_msg(r.col(0)), to_msg(r.col(1)), to_msg(r.col(2))),
                           to_msg(x.translation()));
}
Eigen::Isometry3d from_msg(const msg::SimTransform& t) {
  Eigen::Isometry3d x = Eigen::Isometry3d::Identity();
  x.linear().col(0) = from_msg(t.rotation().col0());
  x.linear().col(1) = from_msg(t.rotation().col1());
  x.linear().col(2) = from_msg(t.rotation().col2());
  x.translation() = from_msg(t.translation());
  return x;
}

msg::SimLink to_msg(const LinkGeometry& l) {
  return msg::SimLink(
      l.shape == LinkGeometry::Shape::kCylinder ? msg::SimShape::Cylinder : msg::SimShape::Box,
      l.feeds_belt, l.belt_drive, to_msg(l.size), to_msg(l.pose), l.belt_speed, l.belt_max_force);
}
msg::SimPlate to_msg(const SuctionPlate& p) {
  return msg::SimPlate(to_msg(p.pose), msg::Vec3(p.extent.x(), p.extent.y(), 0.0), p.cups_x,
                       p.cups_y, p.cup_radius, p.cup_force, p.reach, p.max_tilt);
}

flatbuffers::Offset<msg::SimOptions> to_msg(flatbuffers::FlatBufferBuilder& fbb,
                                            const PhysicsOptions& o) {
  msg::SimOptionsBuilder b(fbb);
  b.add_step(o.step);
  b.add_gravity(o.gravity);
  b.add_friction_box(o.friction_box);
  b.add_friction_trailer(o.friction_trailer);
  b.add_friction_robot(o.friction_robot);
  b.add_contact_omega(o.contact_omega);
  b.add_damping_ratio(o.damping_ratio);
  b.add_box_damping_ratio(o.box_damping_ratio);
  b.add_sleeping(o.sleeping);
  b.add_sleep_speed(o.sleep_speed);
  b.add_sleep_time(o.sleep_time);
  b.add_sleep_ring_speed(o.sleep_ring_speed);
  b.add_sleep_drift(o.sleep_drift);
  b.add_wake_speed(o.wake_speed);
  b.add_wake_depth(o.wake_depth);
  b.add_belt_inertia(o.belt_inertia);
  return b.Finish();
}

// The first problem found, as "sim state: <field>: <what is wrong>".
std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

class Reader {
 public:
  bool ok() const { return error_.empty(); }
  plr::Error error() const { return plr::make_error(PLR_ERR_INVALID, "sim state: " + error_); }

  bool fail(const std::string& field, const std::string& what) {
    if (error_.empty()) error_ = field + ": " + what;
    return false;
  }

  bool finite(const std::string& field, double v) {
    return std::isfinite(v) || fail(field, "must be finite");
  }
  bool in_range(const std::string& field, double v, double lo, double hi) {
    return (std::isfinite(v) && v >= lo && v <= hi) ||
           fail(field, "must be in [" + number(lo) + ", " + number(hi) + "]");
  }
  bool positive(const std::string& field, double v, double hi) {
    return (std::isfinite(v) && v > 0.0 && v <= hi) ||
           fail(field, "must be finite, > 0 and <= " + number(hi));
  }
  bool vector(const std::string& field, const msg::Vec3& v, Eigen::Vector3d& out) {
    out = from_msg(v);
    return out.allFinite() || fail(field, "must be 3 finite numbers");
  }
  bool speed(const std::string& field, const msg::Vec3& v, Eigen::Vector3d& out) {
    out = from_msg(v);
    return (out.allFinite() && out.norm() <= kMaxSpeed) ||
           fail(field, "must be 3 finite numbers, norm <= " + number(kMaxSpeed));
  }
  bool extents(const std::string& field, const msg::Vec3& v, Eigen::Vector3d& out) {
    out = from_msg(v);
    return (out.allFinite() && (out.array() >= kMinLength).all() &&
            (out.array() <= kMaxLength).all()) ||
           fail(field,
                "must be 3 numbers in [" + number(kMinLength) + ", " + number(kMaxLength) + "]");
  }
  bool transform(const std::string& field, const msg::SimTransform& t, Eigen::Isometry3d& out) {
    out = from_msg(t);
    if (!out.matrix().allFinite() || !(out.translation().norm() <= kMaxLength)) {
      return fail(field, "must be finite, within " + number(kMaxLength) + " m");
    }
    const Eigen::Matrix3d r = out.linear();
    if (!((r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() < kUnit) ||
        !(std::abs(r.determinant() - 1.0) < kUnit)) {
      return fail(field, "rotation must be orthonormal and proper");
    }
    return true;
  }
  template <typename T>
  bool count(const std::string& field, const flatbuffers::Vector<T>* v, std::size_t max) {
    if (v == nullptr) return true;
    // The verifier checks only 4-byte alignment of a vector; reading 8-byte
    // members from a misaligned one would be undefined (an empty one may be).
    if (v->size() > 0 && reinterpret_cast<std::uintptr_t>(v->Data()) % alignof(T) != 0) {
      return fail(field, "misaligned");
    }
    return v->size() <= max ||
           fail(field, std::to_string(v->size()) + " entries, at most " + std::to_string(max));
  }

 private:
  std::string error_;
};

template <typename T>
std::size_t size_of(const flatbuffers::Vector<T>* v) {
  return v == nullptr ? 0 : v->size();
}

std::string at(const char* field, std::size_t i) {
  return std::string(field) + "[" + std::to_string(i) + "]";
}

bool read_options(Reader& r, const msg::SimOptions& m, PhysicsOptions& o) {
  o.step = m.step();
  o.gravity = m.gravity();
  o.friction_box = m.friction_box();
  o.friction_trailer = m.friction_trailer();
  o.friction_robot = m.friction_robot();
  o.contact_omega = m.contact_omega();
  o.damping_ratio = m.damping_ratio();
  o.box_damping_ratio = m.box_damping_ratio();
  o.sleeping = m.sleeping();
  o.sleep_speed = m.sleep_speed();
  o.sleep_time = m.sleep_time();
  o.sleep_ring_speed = m.sleep_ring_speed();
  o.sleep_drift = m.sleep_drift();
  o.wake_speed = m.wake_speed();
  o.wake_depth = m.wake_depth();
  o.belt_inertia = m.belt_inertia();
  // The contact damping divides by gravity (the mass a contact carries).
  if (!(r.in_range("options.step", o.step, 1e-5, 0.01) &&
        r.in_range("options.gravity", o.gravity, 0.1, 100) &&
        r.in_range("options.friction_box", o.friction_box, 0, 10) &&
        r.in_range("options.friction_trailer", o.friction_trailer, 0, 10) &&
        r.in_range("options.friction_robot", o.friction_robot, 0, 10) &&
        r.in_range("options.contact_omega", o.contact_omega, 1e-3, 1e5) &&
        r.in_range("options.damping_ratio", o.damping_ratio, 0, 100) &&
        r.in_range("options.box_damping_ratio", o.box_damping_ratio, 0, 100) &&
        r.in_range("options.sleep_speed", o.sleep_speed, 0, 1e3) &&
        r.in_range("options.sleep_time", o.sleep_time, 0, 1e3) &&
        r.in_range("options.sleep_ring_speed", o.sleep_ring_speed, 0, 1e3) &&
        r.in_range("options.sleep_drift", o.sleep_drift, 0, 1e3) &&
        r.in_range("options.wake_speed", o.wake_speed, 0, 1e3) &&
        r.in_range("options.wake_depth", o.wake_depth, 0, 1e3) &&
        r.in_range("options.belt_inertia", o.belt_inertia, 1e-6, 1e6)))
    return false;
  // The contacts are integrated explicitly: a contact oscillation or its
  // damping faster than the step makes them diverge (NaN within a step).
  if (!(o.contact_omega * o.step <= 1.0))
    return r.fail("options.contact_omega",
                  "times options.step must be <= 1 (got " + number(o.contact_omega * o.step) + ")");
  return o.damping_ratio * o.contact_omega * o.step <= 1.0 ||
         r.fail("options.damping_ratio", "times contact_omega and step must be <= 1 (got " +
                                             number(o.damping_ratio * o.contact_omega * o.step) +
                                             ")");
}

bool read_body(Reader& r, const msg::SimBody& m, std::size_t i, Body& b) {
  const std::string f = at("bodies", i);
  if (static_cast<unsigned>(m.mode()) > static_cast<unsigned>(msg::SimBodyMode::MAX)) {
    return r.fail(f + ".mode", "unknown value " + std::to_string(static_cast<unsigned>(m.mode())));
  }
  b.box.id = m.id();
  b.mode = static_cast<Mode>(m.mode());
  b.box.mass = m.mass();
  b.still = m.still();
  b.capacity = m.capacity();
  b.load = m.load();
  if (!r.extents(f + ".size", m.size(), b.box.size) ||
      !r.in_range(f + ".mass", b.box.mass, kMinMass, kMaxMass) ||
      !r.transform(f + ".pose", m.pose(), b.box.pose) ||
      !r.speed(f + ".velocity", m.velocity(), b.v) ||
      !r.speed(f + ".angular_velocity", m.angular_velocity(), b.w) ||
      !r.in_range(f + ".still", b.still, 0, 1e9) || !r.transform(f + ".rest", m.rest(), b.rest) ||
      !r.transform(f + ".grip", m.grip(), b.grip) ||
      !r.in_range(f + ".capacity", b.capacity, 0, 1e9) ||
      !r.in_range(f + ".load", b.load, 0, 1e12)) {
    return false;
  }
  b.radius = 0.5 * b.box.size.norm();
  return true;
}

bool read_link(Reader& r, const msg::SimLink& m, const std::string& f, LinkGeometry& l) {
  if (static_cast<unsigned>(m.shape()) > static_cast<unsigned>(msg::SimShape::MAX)) {
    return r.fail(f + ".shape",
                  "unknown value " + std::to_string(static_cast<unsigned>(m.shape())));
  }
  l.shape = m.shape() == msg::SimShape::Cylinder ? LinkGeometry::Shape::kCylinder
                                                 : LinkGeometry::Shape::kBox;
  l.feeds_belt = m.feeds_belt();
  l.belt_drive = m.belt_drive();
  l.belt_speed = m.belt_speed();
  l.belt_max_force = m.belt_max_force();
  return r.extents(f + ".size", m.size(), l.size) && r.transform(f + ".pose", m.pose(), l.pose) &&
         r.in_range(f + ".belt_speed", l.belt_speed, 0, 100) &&
         r.in_range(f + ".belt_max_force", l.belt_max_force, 0, 1e9);
}

bool read_links(Reader& r, const flatbuffers::Vector<const msg::SimLink*>* v, const char* field,
                std::vector<LinkGeometry>& out) {
  if (!r.count(field, v, kMaxLinks)) return false;
  out.resize(size_of(v));
  for (std::size_t i = 0; i < out.size(); ++i) {
    if (!read_link(r, element(*v, static_cast<flatbuffers::uoffset_t>(i)), at(field, i), out[i]))
      return false;
  }
  return true;
}

// `pump`: the state's pump_max_force field for this plate (0: absent).
bool read_plate(Reader& r, const msg::SimPlate* m, double pump, const char* field,
                std::optional<SuctionPlate>& out) {
  if (m == nullptr) return true;
  const std::string f = field;
  SuctionPlate p;
  Eigen::Vector3d extent;
  p.cups_x = m->cups_x();
  p.cups_y = m->cups_y();
  p.cup_radius = m->cup_radius();
  p.cup_force = m->cup_force();
  p.reach = m->reach();
  p.max_tilt = m->max_tilt();
  if (!r.transform(f + ".pose", m->pose(), p.pose) ||
      !r.vector(f + ".extent", m->extent(), extent) ||
      !r.positive(f + ".extent.x", extent.x(), kMaxLength) ||
      !r.positive(f + ".extent.y", extent.y(), kMaxLength) ||
      !r.in_range(f + ".cups_x", p.cups_x, 1, kMaxCups) ||
      !r.in_range(f + ".cups_y", p.cups_y, 1, kMaxCups) ||
      !r.in_range(f + ".cup_radius", p.cup_radius, 0, kMaxLength) ||
      !r.in_range(f + ".cup_force", p.cup_force, 0, 1e9) ||
      !r.in_range(f + ".reach", p.reach, 0, kMaxLength) ||
      !r.in_range(f + ".max_tilt", p.max_tilt, 0, M_PI)) {
    return false;
  }
  p.extent = extent.head<2>();
  // Bytes written before the state had the field carry the pump's limit in
  // extent.z; 0 in both: the default.
  const bool legacy = pump == 0.0;
  if (legacy) pump = extent.z();
  if (pump != 0.0) {
    if (!r.positive(legacy ? f + ".extent.z (pump_max_force)" : f + "_pump_max_force", pump, 1e9))
      return false;
    p.pump_max_force = pump;
  }
  out = p;
  return true;
}

bool read_state(Reader& r, const msg::SimulationState& m, Trailer& trailer, PhysicsOptions& options,
                State& s) {
  Eigen::Vector3d size;
  if (!r.extents("trailer_size", *m.trailer_size(), size)) return false;
  trailer = {size.x(), size.y(), size.z()};
  if (!read_options(r, *m.options(), options)) return false;
  s.time = m.time();
  if (!r.in_range("time", s.time, 0, 1e9)) return false;

  if (!r.count("bodies", m.bodies(), kMaxBodies)) return false;
  const std::size_t n = size_of(m.bodies());
  s.bodies.resize(n);
  std::unordered_set<std::uint32_t> ids;
  for (std::size_t i = 0; i < n; ++i) {
    if (!read_body(r, element(*m.bodies(), static_cast<flatbuffers::uoffset_t>(i)), i, s.bodies[i]))
      return false;
    // Pairs, grips and unload events name boxes by id.
    if (!ids.insert(s.bodies[i].box.id).second)
      return r.fail(at("bodies", i) + ".id",
                    "box " + std::to_string(s.bodies[i].box.id) + " is there twice");
  }

  if (!r.count("pairs", m.pairs(), kMaxPairs)) return false;
  s.pairs.resize(size_of(m.pairs()));
  for (std::size_t i = 0; i < s.pairs.size(); ++i) {
    const msg::SimPair p = element(*m.pairs(), static_cast<flatbuffers::uoffset_t>(i));
    const std::string f = at("pairs", i);
    if (static_cast<unsigned>(p.kind()) > static_cast<unsigned>(msg::SimPairKind::MAX)) {
      return r.fail(f + ".kind",
                    "unknown value " + std::to_string(static_cast<unsigned>(p.kind())));
    }
    PairState& ps = s.pairs[i];
    ps.key = PairKey{p.a(), p.b(), static_cast<std::uint8_t>(p.kind())};
    ps.twist = p.twist();
    if (!r.vector(f + ".bristle", p.bristle(), ps.bristle) ||
        !r.in_range(f + ".twist", ps.twist, -kMaxLength, kMaxLength))
      return false;
    // A stretch of 1e306 m made the friction force infinite and the step NaN.
    if (!(ps.bristle.norm() <= kMaxLength))
      return r.fail(f + ".bristle", "longer than " + number(kMaxLength) + " m");
    // Looked up by binary search while stepping.
    if (i > 0 && !(s.pairs[i - 1].key < ps.key)) return r.fail(f, "not sorted by (a, b, kind)");
  }

  if (!read_links(r, m.links(), "links", s.links) ||
      !read_links(r, m.link_targets(), "link_targets", s.link_targets)) {
    return false;
  }
  // The contact cache holds the targets' shapes and steps index it by link.
  if (s.links.size() != s.link_targets.size()) {
    return r.fail("links", std::to_string(s.links.size()) + " shapes but " +
                               std::to_string(s.link_targets.size()) + " link_targets");
  }
  if (!read_plate(r, m.plate(), m.plate_pump_max_force(), "plate", s.plate) ||
      !read_plate(r, m.plate_target(), m.plate_target_pump_max_force(), "plate_target",
                  s.plate_target)) {
    return false;
  }
  if (s.plate.has_value() != s.plate_target.has_value()) {
    return r.fail("plate", "plate and plate_target come together");
  }
  if (m.plate_velocity() != nullptr &&
      !r.speed("plate_velocity", *m.plate_velocity(), s.plate_velocity)) {
    return false;
  }

  if (!r.count("unloaded", m.unloaded(), n)) return false;
  for (std::size_t i = 0; i < size_of(m.unloaded()); ++i) {
    const msg::SimUnload u = element(*m.unloaded(), static_cast<flatbuffers::uoffset_t>(i));
    if (!r.in_range(at("unloaded", i) + ".time", u.time(), 0, 1e9)) return false;
    s.unloaded.push_back({u.box_id(), u.time()});
  }
  if (!r.count("suction_events", m.suction_events(), kMaxSuctionEvents)) return false;
  for (std::size_t i = 0; i < size_of(m.suction_events()); ++i) {
    const msg::SimSuctionEvent e =
        element(*m.suction_events(), static_cast<flatbuffers::uoffset_t>(i));
    const std::string f = at("suction_events", i);
    if (static_cast<unsigned>(e.kind()) > static_cast<unsigned>(msg::SimSuctionKind::MAX)) {
      return r.fail(f + ".kind",
                    "unknown value " + std::to_string(static_cast<unsigned>(e.kind())));
    }
    if (!r.in_range(f + ".time", e.time(), 0, 1e9) || !r.finite(f + ".load", e.load()) ||
        !r.finite(f + ".capacity", e.capacity())) {
      return false;
    }
    s.suction_events.push_back(
        {e.box_id(), e.time(), static_cast<SuctionEvent::Kind>(e.kind()), e.load(), e.capacity()});
  }

  if (!r.count("belts", m.belts(), kMaxLinks)) return false;
  s.belts.resize(size_of(m.belts()));
  for (std::size_t i = 0; i < s.belts.size(); ++i) {
    const msg::SimBeltDrive b = element(*m.belts(), static_cast<flatbuffers::uoffset_t>(i));
    const std::string f = at("belts", i);
    s.belts[i] = {b.drive(),      b.max_force(), b.speed_fraction(), b.min_speed_fraction(),
                  b.mean_force(), b.peak_force()};
    if (!r.in_range(f + ".max_force", b.max_force(), 0, 1e9) ||
        !r.in_range(f + ".speed_fraction", b.speed_fraction(), 0, 1) ||
        !r.in_range(f + ".min_speed_fraction", b.min_speed_fraction(), 0, 1) ||
        !r.finite(f + ".mean_force", b.mean_force()) ||
        !r.finite(f + ".peak_force", b.peak_force())) {
      return false;
    }
    // Looked up by binary search when a step starts.
    if (i > 0 && !(s.belts[i - 1].drive < b.drive())) return r.fail(f, "not sorted by drive");
  }
  if (!r.count("robot_forces", m.robot_forces(), kMaxLinks)) return false;
  s.robot_forces.resize(size_of(m.robot_forces()));
  for (std::size_t i = 0; i < s.robot_forces.size(); ++i) {
    const msg::SimRobotForce f = element(*m.robot_forces(), static_cast<flatbuffers::uoffset_t>(i));
    if (!r.vector(at("robot_forces", i) + ".mean", f.mean(), s.robot_forces[i].mean) ||
        !r.vector(at("robot_forces", i) + ".peak", f.peak(), s.robot_forces[i].peak)) {
      return false;
    }
  }

  // Simbody's coordinates: 7 q and 6 u for each body it integrates.
  if (!r.count("slots", m.slots(), n) || !r.count("q", m.q(), 7 * n) ||
      !r.count("u", m.u(), 6 * n)) {
    return false;
  }
  const std::size_t k = size_of(m.slots());
  if (size_of(m.q()) != 7 * k || size_of(m.u()) != 6 * k) {
    return r.fail("q", "need 7 q and 6 u per slot (" + std::to_string(k) + " slots, " +
                           std::to_string(size_of(m.q())) + " q, " +
                           std::to_string(size_of(m.u())) + " u)");
  }
  s.rebuild = m.rebuild();
  std::vector<bool> slotted(n, false);
  for (std::size_t i = 0; i < k; ++i) {
    const int slot = m.slots()->Get(static_cast<flatbuffers::uoffset_t>(i));
    if (slot < 0 || static_cast<std::size_t>(slot) >= n || (i > 0 && slot <= s.slots.back())) {
      return r.fail(at("slots", i), "must be increasing body indices below " + std::to_string(n));
    }
    s.slots.push_back(slot);
    slotted[static_cast<std::size_t>(slot)] = true;
    double norm = 0.0;
    for (std::size_t j = 0; j < 7; ++j) {
      const double q = m.q()->Get(static_cast<flatbuffers::uoffset_t>(7 * i + j));
      if (!r.in_range(at("q", 7 * i + j), q, -kMaxLength, kMaxLength)) return false;
      if (j < 4) norm += q * q;
      s.q.push_back(q);
    }
    if (!(std::abs(norm - 1.0) < kUnit)) return r.fail(at("q", 7 * i), "quaternion not unit");
    for (std::size_t j = 0; j < 6; ++j) {
      const double u = m.u()->Get(static_cast<flatbuffers::uoffset_t>(6 * i + j));
      if (!r.in_range(at("u", 6 * i + j), u, -kMaxSpeed, kMaxSpeed)) return false;
      s.u.push_back(u);
    }
  }
  // Without a pending rebuild, Simbody integrates exactly the awake bodies.
  if (!s.rebuild) {
    for (std::size_t i = 0; i < n; ++i) {
      if (slotted[i] != (s.bodies[i].mode == Mode::kAwake)) {
        return r.fail("slots", "must list exactly the awake bodies when rebuild is false (body " +
                                   std::to_string(i) + ")");
      }
    }
  }
  return true;
}

}  // namespace

std::vector<std::uint8_t> Snapshot::to_bytes() const {
  if (!data_) return {};
  const State& s = data_->state;
  flatbuffers::FlatBufferBuilder fbb(1024 + 400 * s.bodies.size() + 48 * s.pairs.size());
  // Every field written, even zeros: -0.0 equals the default 0.0 and would
  // otherwise come back as +0.0.
  fbb.ForceDefaults(true);
  std::vector<msg::SimBody> bodies;
  bodies.reserve(s.bodies.size());
  for (const Body& b : s.bodies) {
    bodies.emplace_back(b.box.id, static_cast<msg::SimBodyMode>(b.mode), to_msg(b.box.size),
                        b.box.mass, to_msg(b.box.pose), to_msg(b.v), to_msg(b.w), b.still,
                        to_msg(b.rest), to_msg(b.grip), b.capacity, b.load);
  }
  std::vector<msg::SimPair> pairs;
  pairs.reserve(s.pairs.size());
  for (const PairState& p : s.pairs) {
    pairs.emplace_back(p.key.a, p.key.b, static_cast<msg::SimPairKind>(p.key.kind),
                       to_msg(p.bristle), p.twist);
  }
  std::vector<msg::SimLink> links, targets;
  for (const LinkGeometry& l : s.links) links.push_back(to_msg(l));
  for (const LinkGeometry& l : s.link_targets) targets.push_back(to_msg(l));
  std::vector<msg::SimUnload> unloaded;
  for (const UnloadEvent& e : s.unloaded) unloaded.emplace_back(e.box_id, e.time);
  std::vector<msg::SimSuctionEvent> suction;
  for (const SuctionEvent& e : s.suction_events) {
    suction.emplace_back(e.box_id, static_cast<msg::SimSuctionKind>(e.kind), e.time, e.load,
                         e.capacity);
  }
  std::vector<msg::SimBeltDrive> belts;
  for (const BeltLoad& b : s.belts) {
    belts.emplace_back(b.drive, b.max_force, b.speed_fraction, b.min_speed_fraction, b.mean_force,
                       b.peak_force);
  }
  std::vector<msg::SimRobotForce> forces;
  for (const RobotContactForce& f : s.robot_forces)
    forces.emplace_back(to_msg(f.mean), to_msg(f.peak));

  const msg::Vec3 trailer(data_->trailer.width, data_->trailer.height, data_->trailer.depth);
  const auto options = to_msg(fbb, data_->options);
  const std::optional<msg::SimPlate> plate =
      s.plate ? std::optional<msg::SimPlate>(to_msg(*s.plate)) : std::nullopt;
  const std::optional<msg::SimPlate> plate_target =
      s.plate_target ? std::optional<msg::SimPlate>(to_msg(*s.plate_target)) : std::nullopt;
  const msg::Vec3 plate_velocity = to_msg(s.plate_velocity);
  const auto root = msg::CreateSimulationStateDirect(
      fbb, &trailer, options, s.time, &bodies, &pairs, &links, &targets, plate ? &*plate : nullptr,
      plate_target ? &*plate_target : nullptr, &plate_velocity, &unloaded, &suction, &belts,
      &forces, &s.slots, &s.q, &s.u, s.rebuild, s.plate ? s.plate->pump_max_force : 0.0,
      s.plate_target ? s.plate_target->pump_max_force : 0.0);
  msg::FinishSimulationStateBuffer(fbb, root);
  return std::vector<std::uint8_t>(fbb.GetBufferPointer(), fbb.GetBufferPointer() + fbb.GetSize());
}

plr::Expected<Snapshot> Snapshot::from_bytes(const std::uint8_t* data, std::size_t size) {
  const auto error = [](const std::string& what) {
    return plr::make_error(PLR_ERR_INVALID, "sim state: " + what);
  };
  if (data == nullptr || size == 0) return error("no bytes");
  if (size > kMaxBytes) {
    return error(std::to_string(size) + " bytes, at most " + std::to_string(kMaxBytes));
  }
  // FlatBuffers reads scalars in place: give it 8-byte aligned memory.
  std::vector<std::uint64_t> aligned;
  if (reinterpret_cast<std::uintptr_t>(data) % alignof(std::uint64_t) != 0) {
    aligned.resize((size + 7) / 8);
    std::memcpy(aligned.data(), data, size);
    data = reinterpret_cast<const std::uint8_t*>(aligned.data());
  }
  if (size < 8 || !flatbuffers::BufferHasIdentifier(data, msg::SimulationStateIdentifier())) {
    return error("not a SimulationState buffer (no \"PSIM\" file identifier)");
  }
  flatbuffers::Verifier verifier(data, size, /*max_depth=*/8, /*max_tables=*/8);
  if (!msg::VerifySimulationStateBuffer(verifier)) {
    return error("corrupt or truncated FlatBuffer (the verifier refused it)");
  }
  auto d = std::make_shared<Data>();
  Reader reader;
  if (!read_state(reader, *msg::GetSimulationState(data), d->trailer, d->options, d->state)) {
    return reader.error();
  }
  Snapshot snapshot;
  snapshot.data_ = std::move(d);
  return snapshot;
}

}  // namespace plr::sim
