#include "plr/actions/unloader_simulation.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include "plr/msg/sim_state_generated.h"
#include "plr/sim/generators.hpp"
#include "plr/sim/robot_links.hpp"

namespace plr::actions {

using sim::JointVector;

namespace {

// How far (rad or m, any joint) a trajectory may start from the robot's
// configuration: planners start from the observed one, exactly.
constexpr double kStartTolerance = 1e-4;

}  // namespace

struct UnloaderSimulation::Saved {
  sim::Snapshot physics;
  JointVector q;
  std::uint32_t unloaded = 0;
};

struct UnloaderSimulation::Impl {
  const sim::RobotModel* robot = nullptr;
  UnloaderOptions options;
  sim::Simulation sim;
  JointVector q;
  // Boxes unloaded before the physics' own unload events began (a restore
  // brings its events back with it).
  std::uint32_t unloaded_before = 0;
  std::vector<Eigen::Isometry3d> link_poses;  // touches_trailer's, kept between steps

  Impl(const sim::RobotModel& r, const sim::World& truth, const JointVector& q0,
       const UnloaderOptions& o)
      : robot(&r), options(o), sim(truth, o.physics), q(q0) {
    sim.set_fidelity(o.fidelity);
    move_robot(q, false);
  }

  std::uint32_t unloaded() const {
    return unloaded_before + static_cast<std::uint32_t>(sim.unloaded().size());
  }

  // Robot links and plate follow q; the belt runs while the conveyor is on.
  void move_robot(const JointVector& at, bool conveyor) {
    sim.set_robot_links(sim::robot_link_geometry(*robot, at, conveyor ? options.belt_speed : 0.0));
    sim.set_suction_plate(sim::suction_plate_at(*robot, at));
  }

  // Robot shapes beyond the side walls, the ceiling or the front wall (the
  // floor is where the scoop works, so touching it is not counted). The
  // shapes are the URDF's: the physics stands a cube in for a sphere, whose
  // corners reach out where the robot does not.
  bool touches_trailer(const JointVector& at) {
    const auto& t = sim.trailer();
    robot->forward_kinematics(at, link_poses);
    for (std::size_t l = 0; l < robot->links().size(); ++l) {
      for (const auto& shape : robot->links()[l].shapes) {
        const Eigen::Isometry3d pose = link_poses[l] * shape.origin;
        const Eigen::Vector3d c = pose.translation(), e = sim::half_extents(shape, pose);
        if (c.x() + e.x() < 0) continue;  // outside the trailer, behind its open rear
        if (std::abs(c.y()) + e.y() > t.width / 2 || c.z() + e.z() > t.height ||
            c.x() + e.x() > t.depth)
          return true;
      }
    }
    return false;
  }

  // A box not held whose centre is over a running belt, at most a box
  // height above its surface.
  bool belt_loaded() const {
    const auto held = sim.held_boxes();
    for (const auto& box : sim.world().boxes) {
      if (std::find(held.begin(), held.end(), box.id) != held.end()) continue;
      for (const auto& link : sim.robot_links()) {
        if (link.belt_speed <= 0.0) continue;
        const Eigen::Vector3d local = link.pose.inverse() * box.pose.translation();
        if (std::abs(local.x()) < link.size.x() / 2 && std::abs(local.y()) < link.size.y() / 2 &&
            local.z() > 0.0 && local.z() < link.size.z() / 2 + box.size.maxCoeff())
          return true;
      }
    }
    return false;
  }

  void apply_suction(Suction s, const std::vector<bool>& open) {
    if (s == Suction::kOn)
      sim.suction_on(open);
    else if (s == Suction::kOff)
      sim.suction_off();
  }
};

UnloaderSimulation::UnloaderSimulation(const sim::RobotModel& robot, const sim::World& truth,
                                       const JointVector& q, const UnloaderOptions& options)
    : impl_(std::make_unique<Impl>(robot, truth, q, options)) {}
UnloaderSimulation::~UnloaderSimulation() = default;
UnloaderSimulation::UnloaderSimulation(UnloaderSimulation&&) noexcept = default;
UnloaderSimulation& UnloaderSimulation::operator=(UnloaderSimulation&&) noexcept = default;

plr::Expected<Executed> UnloaderSimulation::execute(const Motion& motion,
                                                    const PeriodObserver& observer) {
  Impl& m = *impl_;
  // A non-finite point would reach the contact model and Simbody as NaN poses.
  for (std::size_t i = 0; i < motion.points.size(); ++i) {
    if (!std::isfinite(motion.points[i].time_s) || !motion.points[i].position.allFinite())
      return plr::make_error(PLR_ERR_INVALID, fmt::format("trajectory point {} is not finite", i));
    if (i > 0 && motion.points[i].time_s < motion.points[i - 1].time_s)
      return plr::make_error(PLR_ERR_INVALID, "trajectory times must not decrease");
  }
  if (!std::isfinite(motion.settle_s))
    return plr::make_error(PLR_ERR_INVALID, "settle time is not finite");
  if (!motion.points.empty()) {
    const double off = (motion.points.front().position - m.q).cwiseAbs().maxCoeff();
    // A trajectory planned from another state would make the robot jump: a
    // robot controller refuses it, and so does the simulator.
    if (!(off <= kStartTolerance))
      return plr::make_error(
          PLR_ERR_STATE,
          fmt::format("the trajectory starts {:.4f} (rad or m) away from the robot's configuration",
                      off));
  }
  const auto before = m.sim.world();
  const auto events_before = m.sim.unloaded().size();
  const auto suction_before = m.sim.suction_events().size();
  const double start_time = m.sim.time();
  const double period = m.options.control_period_s;
  Executed out;
  bool touching = false;
  auto advance = [&](double dt, const JointVector& q) {
    m.move_robot(q, motion.conveyor);
    m.sim.step(dt);
    const bool now = m.touches_trailer(q);
    if (now && !touching) ++out.robot_trailer_contacts;
    touching = now;
    if (observer) observer(q);
  };
  m.apply_suction(motion.before, motion.cups_open);
  // The base's drive against what the boxes push back on the robot: the
  // force along the base's motion, low-pass filtered.
  double push = 0.0;
  auto pushed_back = [&](double dt, double direction) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (const auto& f : m.sim.robot_contact_forces()) sum += f.mean;
    const double against = -direction * sum.x();
    push += (against - push) * std::min(1.0, dt / m.options.base_push_filter_s);
    out.peak_push_force = std::max(out.peak_push_force, push);
    return push > m.options.base_max_push_force;
  };
  JointVector now = m.q;
  for (std::size_t i = 1; i < motion.points.size() && !out.stalled; ++i) {
    const auto& a = motion.points[i - 1];
    const auto& b = motion.points[i];
    const double span = b.time_s - a.time_s;
    const int steps = std::max(1, static_cast<int>(std::ceil(span / period)));
    const double base_move = b.position[sim::kBaseX] - a.position[sim::kBaseX];
    for (int k = 1; k <= steps; ++k) {
      const double f = static_cast<double>(k) / steps;
      now = a.position + f * (b.position - a.position);
      advance(span / steps, now);
      if (base_move == 0.0) {
        push = 0.0;
        continue;
      }
      if (pushed_back(span / steps, base_move > 0.0 ? 1.0 : -1.0)) {
        // The drive gives up: the robot stops where it is.
        out.stalled = true;
        out.stall_force = push;
        out.stall_after_s = m.sim.time() - start_time;
        break;
      }
    }
  }
  if (!motion.points.empty()) m.q = out.stalled ? now : motion.points.back().position;
  m.apply_suction(motion.after, motion.cups_open);
  for (double t = 0; t < motion.settle_s; t += period) advance(period, m.q);
  // The belt keeps running until nothing lies on it (a real conveyor does
  // not stop between actions), bounded by carry_max_s.
  if (motion.conveyor) {
    for (double t = 0; t < m.options.carry_max_s && m.belt_loaded(); t += period)
      advance(period, m.q);
  }
  out.held = m.sim.held_boxes();
  const auto after = m.sim.world();
  std::map<std::uint32_t, Eigen::Vector3d> end;
  for (const auto& b : after.boxes) end[b.id] = b.pose.translation();
  for (const auto& b : before.boxes) {
    auto it = end.find(b.id);
    if (it == end.end() || (it->second - b.pose.translation()).norm() > 0.01)
      out.moved.push_back(b.id);
  }
  const auto& events = m.sim.unloaded();
  for (auto i = events_before; i < events.size(); ++i) {
    out.unloaded.push_back(events[i].box_id);
    out.unloaded_after_s.push_back(events[i].time - start_time);
  }
  const auto& suction = m.sim.suction_events();
  for (auto i = suction_before; i < suction.size(); ++i) {
    if (suction[i].kind == sim::SuctionEvent::Kind::kDropped ||
        suction[i].kind == sim::SuctionEvent::Kind::kRefused)
      out.suction.push_back(suction[i]);
  }
  out.sim_time_s = m.sim.time();
  return out;
}

const sim::RobotModel& UnloaderSimulation::robot() const {
  return *impl_->robot;
}
sim::World UnloaderSimulation::truth() const {
  return impl_->sim.world();
}
sim::World UnloaderSimulation::perceived() const {
  return sim::without_masses(impl_->sim.world());
}
const JointVector& UnloaderSimulation::q() const {
  return impl_->q;
}
std::vector<std::uint32_t> UnloaderSimulation::held() const {
  return impl_->sim.held_boxes();
}
std::uint32_t UnloaderSimulation::boxes_unloaded() const {
  return impl_->unloaded();
}
double UnloaderSimulation::time() const {
  return impl_->sim.time();
}
const sim::Simulation& UnloaderSimulation::physics() const {
  return impl_->sim;
}

void UnloaderSimulation::set_fidelity(sim::Fidelity fidelity) {
  impl_->options.fidelity = fidelity;
  impl_->sim.set_fidelity(fidelity);
}

std::shared_ptr<const UnloaderSimulation::Saved> UnloaderSimulation::save() const {
  return std::make_shared<const Saved>(Saved{impl_->sim.snapshot(), impl_->q, impl_->unloaded()});
}

void UnloaderSimulation::restore(const Saved& saved) {
  Impl& m = *impl_;
  m.sim.restore(saved.physics);
  m.q = saved.q;
  // The restored physics carries its own unload events; count from there.
  m.unloaded_before = saved.unloaded - static_cast<std::uint32_t>(m.sim.unloaded().size());
  m.move_robot(m.q, false);
}

const sim::Snapshot& UnloaderSimulation::physics_of(const Saved& saved) {
  return saved.physics;
}
const sim::JointVector& UnloaderSimulation::q_of(const Saved& saved) {
  return saved.q;
}
std::uint32_t UnloaderSimulation::unloaded_of(const Saved& saved) {
  return saved.unloaded;
}
std::shared_ptr<const UnloaderSimulation::Saved> UnloaderSimulation::make_saved(
    sim::Snapshot physics, const sim::JointVector& q, std::uint32_t unloaded) {
  return std::make_shared<const Saved>(Saved{std::move(physics), q, unloaded});
}

plr::Status UnloaderSimulation::set_masses(
    const std::vector<std::pair<std::uint32_t, double>>& masses) {
  Impl& m = *impl_;
  // Through the state's bytes: the physics keeps its state private, and the
  // bytes carry every double exactly, so only the masses change.
  const std::vector<std::uint8_t> bytes = m.sim.snapshot().to_bytes();
  msg::SimulationStateT state;
  msg::GetSimulationState(bytes.data())->UnPackTo(&state);
  std::map<std::uint32_t, std::size_t> at;
  for (std::size_t i = 0; i < state.bodies.size(); ++i) {
    const msg::SimBody& b = state.bodies[i];
    if (b.mode() != msg::SimBodyMode::Gone) at.emplace(b.id(), i);
  }
  for (const auto& [id, mass] : masses) {
    if (!at.count(id))
      return plr::make_error(PLR_ERR_INVALID, fmt::format("set_masses: no box {}", id));
    if (!std::isfinite(mass) || !(mass > 0))
      return plr::make_error(PLR_ERR_INVALID,
                             fmt::format("set_masses: box {}: mass must be finite and > 0", id));
  }
  for (const auto& [id, mass] : masses) {
    msg::SimBody& b = state.bodies[at[id]];
    b = msg::SimBody(b.id(), b.mode(), b.size(), mass, b.pose(), b.velocity(), b.angular_velocity(),
                     b.still(), b.rest(), b.grip(), b.capacity(), b.load());
  }
  flatbuffers::FlatBufferBuilder fbb;
  msg::FinishSimulationStateBuffer(fbb, msg::SimulationState::Pack(fbb, &state));
  auto snapshot = sim::Snapshot::from_bytes(fbb.GetBufferPointer(), fbb.GetSize());
  if (!snapshot) return snapshot.error();
  m.sim.restore(*snapshot);
  return {};
}

}  // namespace plr::actions
