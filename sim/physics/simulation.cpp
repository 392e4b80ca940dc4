// Orchestrates one fixed step: move robot shapes and held boxes, compute
// contact, let Simbody integrate the awake boxes, then sleep, wake, unload
// and check the suction hold.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "contact.hpp"
#include "multibody.hpp"
#include "plr/sim/physics.hpp"
#include "state.hpp"
#include "support.hpp"

namespace plr::sim {

using detail::Body;
using detail::Mode;
using detail::Mover;
using detail::State;
using detail::Wrench;

Snapshot::Snapshot() = default;
Snapshot::~Snapshot() = default;
Snapshot::Snapshot(const Snapshot&) = default;
Snapshot& Snapshot::operator=(const Snapshot&) = default;
bool Snapshot::empty() const {
  return !data_;
}
double Snapshot::time() const {
  return data_ ? data_->state.time : 0.0;
}
World Snapshot::world() const {
  World w;
  if (!data_) return w;
  w.trailer = data_->trailer;
  for (const Body& b : data_->state.bodies) {
    if (b.mode != Mode::kGone) w.boxes.push_back(b.box);
  }
  return w;
}
const PhysicsOptions& Snapshot::options() const {
  static const PhysicsOptions defaults;
  return data_ ? data_->options : defaults;
}

namespace {

constexpr double kLoadFilter = 0.02;  // s; cups are compliant, contact spikes are not felt

// A box woken by a neighbour's motion that did not disturb it stays where it
// was and in balance; waiting the full sleep_time for it is most of what
// such wakes cost. Balanced: the contact force differs from its weight by
// under kBalancedForce of it, and the torque about its centre is under its
// weight times kBalancedArm (a box whose centre of mass lies 1 cm beyond the
// edge it rests on feels 5x that). Such a box sleeps after
// kBalancedSleepFraction of sleep_time.
constexpr double kBalancedForce = 0.05;
constexpr double kBalancedArm = 0.002;  // m
constexpr double kBalancedSleepFraction = 0.2;
// The divergence guard, as physics engines have one (PhysX's maximum
// velocities): the explicit contacts can still go unstable on a box the
// tuning did not foresee (a 7 cm thin one, found by fuzzing the state bytes),
// and its speed then grows a hundredfold a step until Simbody meets a NaN.
// No box in a trailer comes near these speeds; one past them is stopped.
constexpr double kMaxBoxSpeed = 100.0;  // m/s
constexpr double kMaxBoxSpin = 1000.0;  // rad/s

// A pose carried from `a` to `b` over a step() call at constant twist (v,
// w): what does not depend on how far into the call is computed once.
struct Path {
  Path(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b, double duration)
      : qa(a.rotation()), qb(b.rotation()), pa(a.translation()), pb(b.translation()) {
    v = (b.translation() - a.translation()) / duration;
    const Eigen::AngleAxisd r(b.rotation() * a.rotation().transpose());
    w = r.axis() * r.angle() / duration;
  }
  // The pose a fraction `s` into the call.
  Eigen::Isometry3d at(double s) const {
    Eigen::Isometry3d x = Eigen::Isometry3d::Identity();
    x.linear() = qa.slerp(s, qb).toRotationMatrix();
    x.translation() = (1.0 - s) * pa + s * pb;
    return x;
  }
  Eigen::Quaterniond qa, qb;
  Eigen::Vector3d pa, pb, v, w;
};

double bounding_radius(const LinkGeometry& l) {
  return l.shape == LinkGeometry::Shape::kCylinder ? std::hypot(l.size.x(), 0.5 * l.size.z())
                                                   : 0.5 * l.size.norm();
}

}  // namespace

struct Simulation::Impl {
  PhysicsOptions options;
  Trailer trailer;
  State state;
  detail::Contacts contacts;
  detail::Multibody multibody;
  std::vector<int> slots;  // body index of each Simbody body
  bool rebuild = true;     // the awake set changed
  // The held and awake bodies, ascending: a wall's boxes sleep, and the
  // per-step loops over the bodies visit these without reading the rest.
  // Stale after any change of a body's mode.
  std::vector<int> moving;
  bool moving_stale = true;
  // Set by restore(): the Simbody system to rebuild before the next step.
  struct Pending {
    std::vector<int> slots;
    std::vector<double> q, u;
  };
  std::optional<Pending> pending;
  PhysicsStats stats;                   // work done; not part of the simulated state
  Fidelity fidelity = Fidelity::kFull;  // a setting, not part of the state
  // Scratch, reused every step.
  std::vector<Mover> movers;
  std::vector<Wrench> wrenches;
  std::vector<int> wake;
  struct Velocity {
    Eigen::Vector3d v, w;
  };
  std::vector<Velocity> undamped;  // awake boxes' velocities before damping
  // Per robot shape: index of its belt drive in state.belts, -1 if no belt
  // runs on it; per drive, its fastest belt's speed. Set by step().
  std::vector<int> link_drive;
  std::vector<double> drive_speed, drive_load;

  Impl(const World& world, const PhysicsOptions& o)
      : options(o), trailer(world.trailer), contacts(o, world.trailer) {
    if (!(o.step > 0.0) || !(o.contact_omega > 0.0) || !(o.belt_inertia > 0.0)) {
      throw std::invalid_argument(
          "PhysicsOptions: step, contact_omega and belt_inertia must be > 0");
    }
    for (const Box& b : world.boxes) {
      if (!(b.mass > 0.0)) {
        throw std::invalid_argument("Simulation: box " + std::to_string(b.id) +
                                    " has no mass (the simulator needs the true world)");
      }
      Body body;
      body.box = b;
      body.radius = 0.5 * b.size.norm();
      state.bodies.push_back(body);
    }
    contacts.set_boxes(state.bodies);
  }

  explicit Impl(const Snapshot::Data& saved)
      : options(saved.options), trailer(saved.trailer), contacts(saved.options, saved.trailer) {
    load(saved);
  }

  // Everything from the snapshot; Simbody's system is rebuilt lazily at the
  // next step, from the exact coordinates.
  void load(const Snapshot::Data& saved) {
    options = saved.options;
    trailer = saved.trailer;
    state = saved.state;
    state.slots.clear();
    state.q.clear();
    state.u.clear();
    contacts = detail::Contacts(options, trailer);
    contacts.set_boxes(state.bodies);
    contacts.set_links(state.link_targets);
    pending = Pending{saved.state.slots, saved.state.q, saved.state.u};
    rebuild = saved.state.rebuild;
    moving_stale = true;
    by_id.clear();  // another world may hold as many boxes
  }

  void wake_body(int i) {
    Body& b = state.bodies[static_cast<std::size_t>(i)];
    if (b.mode != Mode::kAsleep) return;
    b.mode = Mode::kAwake;
    b.still = 0.0;
    rebuild = true;
    moving_stale = true;
  }

  // The cups let go of held box i, more than their `share` could hold: it
  // falls under physics from here.
  void drop(int i, double share) {
    Body& b = state.bodies[static_cast<std::size_t>(i)];
    b.mode = Mode::kAwake;
    b.still = 0.0;
    rebuild = true;
    moving_stale = true;
    state.suction_events.push_back(
        {b.box.id, state.time, SuctionEvent::Kind::kDropped, b.load, share * b.capacity});
  }

  const std::vector<int>& moving_bodies() {
    if (moving_stale) {
      moving.clear();
      for (std::size_t i = 0; i < state.bodies.size(); ++i) {
        const Mode mode = state.bodies[i].mode;
        if (mode == Mode::kAwake || mode == Mode::kHeld) moving.push_back(static_cast<int>(i));
      }
      moving_stale = false;
    }
    return moving;
  }

  // Adaptive fidelity: boxes far from the action freeze early. Scratch of
  // freeze_far(): (box id, body index) sorted by id; per body, its group's
  // root, and flags.
  std::vector<std::pair<std::uint32_t, int>> by_id;
  std::vector<int> group;
  std::vector<std::uint8_t> active, touches, source, ready;

  int index_of(std::uint32_t id) const {
    const auto it = std::lower_bound(by_id.begin(), by_id.end(), std::make_pair(id, -1));
    return it != by_id.end() && it->first == id ? it->second : -1;
  }
  int root(int i) {
    while (group[static_cast<std::size_t>(i)] != i) {
      const auto k = static_cast<std::size_t>(i);
      group[k] = group[static_cast<std::size_t>(group[k])];
      i = group[k];
    }
    return i;
  }

  // Before a fixed step's contacts: the awake and held boxes joined by the
  // last step's box-box contacts (state.pairs) into groups. A group is in
  // the action when one of its boxes is held, touches a robot shape or moves
  // at wake_speed or more; its boxes are marked `active`. A group that is
  // not has no contact path to the action: once each of its boxes has been
  // slow (Body::still) for kBalancedSleepFraction of sleep_time, they all
  // freeze, without waiting for balance or the rest of sleep_time. Only the
  // state decides (pairs, speeds, still), so restored runs repeat.
  void freeze_far() {
    const std::size_t n = state.bodies.size();
    active.assign(n, 0);
    const std::vector<int>& list = moving_bodies();
    if (list.empty()) return;
    if (by_id.size() != n) {
      by_id.clear();
      for (std::size_t i = 0; i < n; ++i)
        by_id.emplace_back(state.bodies[i].box.id, static_cast<int>(i));
      std::sort(by_id.begin(), by_id.end());
    }
    group.resize(n);
    touches.assign(n, 0);
    source.assign(n, 0);
    ready.assign(n, 0);
    for (const int i : list) group[static_cast<std::size_t>(i)] = i;
    const auto moves = [&](int i) {
      if (i < 0) return false;
      const Mode mode = state.bodies[static_cast<std::size_t>(i)].mode;
      return mode == Mode::kAwake || mode == Mode::kHeld;
    };
    for (const detail::PairState& p : state.pairs) {
      if (p.key.kind == 1) {  // box and robot shape (PairKey)
        const int i = index_of(p.key.a);
        if (i >= 0) touches[static_cast<std::size_t>(i)] = 1;
      } else if (p.key.kind == 0) {
        const int a = index_of(p.key.a), b = index_of(p.key.b);
        if (moves(a) && moves(b)) group[static_cast<std::size_t>(root(a))] = root(b);
      }
    }
    const double slow_enough = kBalancedSleepFraction * options.sleep_time;
    for (const int i : list) {
      const auto k = static_cast<std::size_t>(i);
      const Body& b = state.bodies[k];
      const auto r = static_cast<std::size_t>(root(i));
      if (b.mode == Mode::kHeld || touches[k] != 0 ||
          b.v.norm() + b.w.norm() * b.radius >= options.wake_speed)
        source[r] = 1;
      ready[r] = 1;
    }
    for (const int i : list) {
      const Body& b = state.bodies[static_cast<std::size_t>(i)];
      if (b.still < slow_enough) ready[static_cast<std::size_t>(root(i))] = 0;
    }
    bool froze = false;
    for (const int i : list) {
      const auto k = static_cast<std::size_t>(i);
      const auto r = static_cast<std::size_t>(root(i));
      active[k] = source[r];
      if (source[r] != 0 || ready[r] == 0) continue;
      Body& b = state.bodies[k];
      b.mode = Mode::kAsleep;
      b.v.setZero();
      b.w.setZero();
      ++stats.frozen;
      froze = true;
    }
    if (froze) {
      rebuild = true;
      moving_stale = true;
    }
  }

  // Simbody system for `members` (body indices). Bodies already integrated
  // keep their exact coordinates; `q`, `u` (from a snapshot) override them.
  void build_multibody(const std::vector<int>& members, const std::vector<double>* q,
                       const std::vector<double>* u) {
    std::vector<detail::FreeBody> free;
    std::vector<int> old_slot(state.bodies.size(), -1);
    for (std::size_t s = 0; s < slots.size(); ++s) {
      old_slot[static_cast<std::size_t>(slots[s])] = static_cast<int>(s);
    }
    for (const int i : members) {
      const Body& b = state.bodies[static_cast<std::size_t>(i)];
      detail::FreeBody f{b.box.mass, b.box.size, b.box.pose, b.v, b.w, {}, {}};
      if (q != nullptr) {
        const auto k = static_cast<long>(free.size());
        f.q.assign(q->begin() + 7 * k, q->begin() + 7 * k + 7);
        f.u.assign(u->begin() + 6 * k, u->begin() + 6 * k + 6);
      } else if (old_slot[static_cast<std::size_t>(i)] >= 0) {
        multibody.coordinates(old_slot[static_cast<std::size_t>(i)], f.q, f.u);
      }
      free.push_back(std::move(f));
    }
    slots = members;
    if (!slots.empty()) multibody.build(free, options.gravity, state.time);
  }

  void rebuild_awake() {
    std::vector<int> members;
    for (std::size_t i = 0; i < state.bodies.size(); ++i) {
      if (state.bodies[i].mode == Mode::kAwake) members.push_back(static_cast<int>(i));
    }
    build_multibody(members, nullptr, nullptr);
    rebuild = false;
    ++stats.rebuilds;
  }

  void place_held(const Eigen::Isometry3d& plate, const Eigen::Vector3d& v,
                  const Eigen::Vector3d& w) {
    for (const int i : moving_bodies()) {
      Body& b = state.bodies[static_cast<std::size_t>(i)];
      if (b.mode != Mode::kHeld) continue;
      b.box.pose = plate * b.grip;
      b.w = w;
      b.v = v + w.cross(b.box.pose.translation() - plate.translation());
    }
  }

  // The nose conveyor hands boxes to the robot's body conveyor at its -x end:
  // a box lying on a belt whose trailing edge reaches that end has left the
  // trailer. Lying on it: its lowest point near the belt's surface (a box
  // pushed along the floor in front of the base is not on the belt), and
  // part of it still over the belt (a box on the floor behind the end lies
  // in the plane of a raised belt, not on it).
  static constexpr double kHandover = 0.05;  // m; the base's face stops a box this short of the end
  static constexpr double kOnBelt = 0.03;    // m between the box's lowest point and the belt
  // The shapes whose belt hands boxes on, with their inverse poses: the
  // shapes stand still for the fixed steps of a step() call, so they are
  // set once per call (set_belt_ends), not per box and step.
  struct BeltEnd {
    std::size_t link;  // in state.links
    Eigen::Isometry3d to_local;
  };
  std::vector<BeltEnd> belt_ends;

  void set_belt_ends() {
    belt_ends.clear();
    for (std::size_t l = 0; l < state.links.size(); ++l) {
      const LinkGeometry& g = state.links[l];
      if (g.belt_speed > 0.0 && !g.feeds_belt) belt_ends.push_back({l, g.pose.inverse()});
    }
  }

  bool unloaded_by_belt(const Body& b) const {
    for (const BeltEnd& end : belt_ends) {
      const LinkGeometry& l = state.links[end.link];
      const Eigen::Vector3d local = end.to_local * b.box.pose.translation();
      // Quick reject on the centre alone: no part of the box reaches further
      // from it than its half diagonal (the margin covers rounding).
      const double reach_max = b.radius + 1e-6;
      if (std::abs(local.y()) >= 0.5 * l.size.y() ||
          local.z() <= 0.5 * l.size.z() - kOnBelt - 1e-6 ||
          local.z() >= 0.5 * l.size.z() + kOnBelt + reach_max ||
          local.x() - reach_max >= -0.5 * l.size.x() + kHandover + 1e-6 ||
          local.x() + reach_max <= -0.5 * l.size.x() - 1e-6) {
        continue;
      }
      const Eigen::Matrix3d r = l.pose.linear().transpose() * b.box.pose.linear();
      const Eigen::Vector3d reach = r.cwiseAbs() * (0.5 * b.box.size);
      const double above_belt = local.z() - reach.z() - 0.5 * l.size.z();
      if (local.x() - reach.x() < -0.5 * l.size.x() + kHandover &&
          local.x() + reach.x() > -0.5 * l.size.x() && std::abs(local.y()) < 0.5 * l.size.y() &&
          above_belt > -kOnBelt && above_belt < kOnBelt) {
        return true;
      }
    }
    return false;
  }

  // Fast fidelity: a box let go over a running belt leaves on it (the belt
  // carries what falls on it to the robot's body conveyor): its centre over
  // the belt's surface, at most its largest side above it (as a box lying
  // on the belt is seen by the unloader). A box let go higher is left to
  // the physics: it may fall aside.
  bool over_running_belt(const Body& b) const {
    for (const LinkGeometry& l : state.link_targets) {
      if (!(l.belt_speed > 0.0)) continue;
      const Eigen::Vector3d local = l.pose.inverse() * b.box.pose.translation();
      if (std::abs(local.x()) < 0.5 * l.size.x() && std::abs(local.y()) < 0.5 * l.size.y() &&
          local.z() > 0.0 && local.z() < 0.5 * l.size.z() + b.box.size.maxCoeff())
        return true;
    }
    return false;
  }

  void remove(int i) {
    Body& b = state.bodies[static_cast<std::size_t>(i)];
    const bool was_awake = b.mode == Mode::kAwake;
    b.mode = Mode::kGone;
    if (was_awake) rebuild = true;
    moving_stale = true;
    contacts.box_removed();
    // What rested on or leaned against it must notice that it is gone. At
    // fast fidelity only what it held up does (the support rule).
    const bool fast = fidelity == Fidelity::kFast;
    if (fast) contacts.update_broad_phase(state.bodies, moving_bodies());
    const Eigen::Vector3d e =
        b.box.pose.linear().cwiseAbs() * (0.5 * b.box.size) + Eigen::Vector3d::Constant(0.02);
    const Eigen::Vector3d lo = b.box.pose.translation() - e, hi = b.box.pose.translation() + e;
    for (std::size_t j = 0; j < state.bodies.size(); ++j) {
      const Body& o = state.bodies[j];
      if (o.mode != Mode::kAsleep) continue;
      const Eigen::Vector3d oe = o.box.pose.linear().cwiseAbs() * (0.5 * o.box.size);
      const Eigen::Vector3d olo = o.box.pose.translation() - oe;
      const Eigen::Vector3d ohi = o.box.pose.translation() + oe;
      if ((olo.array() <= hi.array()).all() && (lo.array() <= ohi.array()).all() &&
          (!fast ||
           !detail::supported(state.bodies, contacts.broad_phase(), static_cast<int>(j)))) {
        wake_body(static_cast<int>(j));
      }
    }
  }

  // Drives of the belts switched on for this step() call (new ones start at
  // full speed) and the call's measurements reset.
  void prepare_loads() {
    link_drive.assign(state.links.size(), -1);
    for (std::size_t l = 0; l < state.links.size(); ++l) {
      const LinkGeometry& g = state.links[l];
      if (!(g.belt_speed > 0.0)) continue;
      auto it = std::lower_bound(state.belts.begin(), state.belts.end(), g.belt_drive,
                                 [](const BeltLoad& d, int id) { return d.drive < id; });
      if (it == state.belts.end() || it->drive != g.belt_drive) {
        BeltLoad d;
        d.drive = g.belt_drive;
        d.max_force = g.belt_max_force;
        it = state.belts.insert(it, d);
      }
      link_drive[l] = static_cast<int>(it - state.belts.begin());
    }
    drive_speed.assign(state.belts.size(), 0.0);
    std::vector<bool> limit_set(state.belts.size(), false);
    for (std::size_t l = 0; l < state.links.size(); ++l) {
      const int d = link_drive[l];
      if (d < 0) continue;
      const auto k = static_cast<std::size_t>(d);
      drive_speed[k] = std::max(drive_speed[k], state.links[l].belt_speed);
      if (!limit_set[k]) state.belts[k].max_force = state.links[l].belt_max_force;
      limit_set[k] = true;
    }
    for (std::size_t k = 0; k < state.belts.size(); ++k) {
      BeltLoad& d = state.belts[k];
      // A belt switched off stands; switched on again it starts at full speed.
      if (drive_speed[k] <= 0.0) d.speed_fraction = 1.0;
      d.min_speed_fraction = d.speed_fraction;
      d.mean_force = d.peak_force = 0.0;
    }
    state.robot_forces.assign(state.links.size(), RobotContactForce{});
  }

  // After this step's contacts: each drive's motor pulls at most its limit;
  // the rest of the load (or, below the limit, the spare force while it runs
  // up) changes the belt's speed through its reflected inertia. A stalled
  // belt holds (gear motors are not driven backwards).
  void update_loads(double dt) {
    const std::vector<Eigen::Vector3d>& link_force = contacts.link_forces();
    const std::vector<double>& belt_force = contacts.belt_forces();
    std::vector<double>& load = drive_load;
    load.assign(state.belts.size(), 0.0);
    for (std::size_t l = 0; l < state.links.size(); ++l) {
      RobotContactForce& f = state.robot_forces[l];
      f.mean += link_force[l];
      if (link_force[l].squaredNorm() > f.peak.squaredNorm()) f.peak = link_force[l];
      if (link_drive[l] >= 0) load[static_cast<std::size_t>(link_drive[l])] += belt_force[l];
    }
    bool limited = false;
    for (std::size_t k = 0; k < state.belts.size(); ++k) {
      BeltLoad& d = state.belts[k];
      d.mean_force += load[k];
      d.peak_force = std::max(d.peak_force, load[k]);
      if (drive_speed[k] <= 0.0) continue;
      if (load[k] > d.max_force || d.speed_fraction < 1.0) {
        const double a = (d.max_force - load[k]) / options.belt_inertia;
        d.speed_fraction = std::clamp(d.speed_fraction + a * dt / drive_speed[k], 0.0, 1.0);
      }
      d.min_speed_fraction = std::min(d.min_speed_fraction, d.speed_fraction);
      limited = limited || d.speed_fraction < 1.0;
    }
    stats.belt_limited_steps += limited;
  }

  // The fraction of cup_force each sealed cup holds with the held boxes'
  // cups (Body::capacity = cups * cup_force) sharing the pump's limit.
  double pump_share() {
    if (!state.plate) return 1.0;
    double sealed = 0.0;
    for (const int i : moving_bodies()) {
      const Body& b = state.bodies[static_cast<std::size_t>(i)];
      if (b.mode == Mode::kHeld) sealed += b.capacity;
    }
    return sealed > state.plate->pump_max_force ? state.plate->pump_max_force / sealed : 1.0;
  }

  // How the robot shapes and the plate move during the current step()
  // call: empty (no plate path) while they stand still.
  std::vector<Path> link_paths;
  std::optional<Path> plate_path;

  void fixed_step(double dt, double fraction, const Eigen::Vector3d& plate_a) {
    // Robot shapes and plate at the start of this step, moving at constant twist.
    movers.resize(state.links.size());
    for (std::size_t l = 0; l < state.links.size(); ++l) {
      Mover& m = movers[l];
      const LinkGeometry& target = state.links[l];
      if (!link_paths.empty()) {
        m.pose = link_paths[l].at(fraction);
        m.v = link_paths[l].v;
        m.w = link_paths[l].w;
      } else {
        m.pose = target.pose;
        m.v.setZero();
        m.w.setZero();
      }
      const int drive = link_drive[l];
      m.belt_dir = drive >= 0 ? Eigen::Vector3d(-m.pose.linear().col(0)) : Eigen::Vector3d::Zero();
      m.belt = drive >= 0
                   ? Eigen::Vector3d(state.belts[static_cast<std::size_t>(drive)].speed_fraction *
                                     target.belt_speed * m.belt_dir)
                   : Eigen::Vector3d::Zero();
      m.speed = m.v.norm() + m.w.norm() * bounding_radius(target);
    }
    bool anything_moves = false;
    if (state.plate) {
      Eigen::Isometry3d plate = state.plate->pose;
      Eigen::Vector3d v = Eigen::Vector3d::Zero(), w = Eigen::Vector3d::Zero();
      if (plate_path) {
        plate = plate_path->at(fraction);
        v = plate_path->v;
        w = plate_path->w;
      }
      place_held(plate, v, w);
      anything_moves = v.squaredNorm() + w.squaredNorm() > 0.0;
    }
    for (const Mover& m : movers) {
      anything_moves = anything_moves || m.speed > 0.0 || m.belt_dir.squaredNorm() > 0.0;
    }
    if (pending) {
      slots.clear();
      build_multibody(pending->slots, &pending->q, &pending->u);
      pending.reset();
    }
    // Fast fidelity freezes far groups as adaptive does.
    const bool adaptive = fidelity == Fidelity::kAdaptive;
    if (fidelity != Fidelity::kFull) freeze_far();
    if (rebuild) rebuild_awake();
    anything_moves = anything_moves || !slots.empty();

    wake.clear();
    if (anything_moves) {
      contacts.compute(state, moving_bodies(), movers, dt, wrenches, wake,
                       adaptive ? &active : nullptr);
      update_loads(dt);
    } else {
      state.pairs.clear();
      detail::clear_wrenches(wrenches, state.bodies.size(), moving_bodies());
    }

    if (!slots.empty()) {
      for (std::size_t s = 0; s < slots.size(); ++s) {
        const Wrench& w = wrenches[static_cast<std::size_t>(slots[s])];
        multibody.set_wrench(static_cast<int>(s), w.force, w.torque);
      }
      undamped.resize(slots.size());
      for (std::size_t s = 0; s < slots.size(); ++s) {
        const Body& b = state.bodies[static_cast<std::size_t>(slots[s])];
        undamped[s] = {b.v, b.w};
      }
      contacts.damp(state, moving_bodies(), dt, wrenches);
      for (std::size_t s = 0; s < slots.size(); ++s) {
        const Body& b = state.bodies[static_cast<std::size_t>(slots[s])];
        if (b.v != undamped[s].v || b.w != undamped[s].w) {
          multibody.add_velocity(static_cast<int>(s), b.v - undamped[s].v, b.w - undamped[s].w);
        }
      }
      multibody.step(dt);
      for (std::size_t s = 0; s < slots.size(); ++s) {
        Body& b = state.bodies[static_cast<std::size_t>(slots[s])];
        multibody.read(static_cast<int>(s), b.box.pose, b.v, b.w);
        if (!(b.v.norm() <= kMaxBoxSpeed && b.w.norm() <= kMaxBoxSpin)) {
          multibody.add_velocity(static_cast<int>(s), -b.v, -b.w);
          b.v.setZero();
          b.w.setZero();
          ++stats.diverged;
        }
      }
      ++stats.dynamic_steps;
      stats.body_steps += static_cast<std::int64_t>(slots.size());
    }
    state.time += dt;
    ++stats.steps;

    for (const int i : wake) wake_body(i);
    const Eigen::Vector3d gravity(0.0, 0.0, -options.gravity);
    // The held boxes' cups share the pump: each box holds what its cups do
    // at the vacuum level the pump keeps on all of them. Of the boxes over
    // their share, the most overloaded lets go; the others' share grows.
    const double share = pump_share();
    int overloaded = -1;
    double worst = 1.0;
    for (const int h : moving_bodies()) {
      const auto i = static_cast<std::size_t>(h);
      Body& b = state.bodies[i];
      if (b.mode != Mode::kHeld) continue;
      // What the cups must supply: the box's inertia and weight plus what
      // its neighbours push on it.
      const Eigen::Vector3d need = b.box.mass * (plate_a - gravity) - wrenches[i].force;
      b.load += (need.norm() - b.load) * std::min(1.0, dt / kLoadFilter);
      const double ratio = b.load / (share * b.capacity);
      if (ratio > worst) {
        worst = ratio;
        overloaded = static_cast<int>(i);
      }
    }
    if (overloaded >= 0) drop(overloaded, share);
    // A sleeping box has not moved, and the belts stand still within a
    // step() call: after the call's first fixed step (fraction 0) it stays
    // where it was found not to be unloaded, and only the moving bodies
    // need a look. A removal wakes its neighbours, which the list does not
    // hold: from there on every body is looked at, as before the list.
    const bool belts_moved = fraction == 0.0;
    const std::size_t n = state.bodies.size();
    if (belts_moved) {
      for (std::size_t i = 0; i < n; ++i) unload_or_sleep(i, dt);
      return;
    }
    const std::vector<int>& listed = moving_bodies();
    for (std::size_t k = 0; k < listed.size(); ++k) {
      const auto i = static_cast<std::size_t>(listed[k]);
      if (!unload_or_sleep(i, dt)) continue;
      for (std::size_t j = i + 1; j < n; ++j) {
        if (state.bodies[j].mode != Mode::kAsleep) unload_or_sleep(j, dt);
      }
      return;
    }
  }

  // Fast fidelity, before a step() call's fixed steps. The boxes the robot
  // shapes and held boxes press into at the call's end (Contacts::pressed)
  // wake, and so do those a held box that moves held up and that nothing
  // else holds up (the support rule). If then no box is awake, the robot
  // and what it holds move kinematically: the call's fixed steps would
  // integrate nothing, so none is taken (true). Otherwise (false) the
  // fixed steps run, the woken boxes in them.
  bool advance_kinematically(long n, double total, const Eigen::Vector3d& plate_v,
                             const Eigen::Vector3d& plate_a) {
    movers.resize(state.links.size());
    for (std::size_t l = 0; l < state.links.size(); ++l) {
      Mover& m = movers[l];
      m.pose = state.links[l].pose;
      m.v = link_paths.empty() ? Eigen::Vector3d::Zero() : link_paths[l].v;
      m.w = link_paths.empty() ? Eigen::Vector3d::Zero() : link_paths[l].w;
      m.belt_dir =
          link_drive[l] >= 0 ? Eigen::Vector3d(-m.pose.linear().col(0)) : Eigen::Vector3d::Zero();
      m.speed = m.v.norm() + m.w.norm() * bounding_radius(state.links[l]);
    }
    Eigen::Vector3d plate_w = Eigen::Vector3d::Zero();
    if (plate_path) plate_w = plate_path->w;
    const bool plate_moves = plate_v.squaredNorm() + plate_w.squaredNorm() > 0.0;
    held_now.clear();
    held_end.clear();
    for (const int i : moving_bodies()) {
      const Body& b = state.bodies[static_cast<std::size_t>(i)];
      if (b.mode != Mode::kHeld || !state.plate) continue;
      held_now.push_back(i);
      held_end.push_back(state.plate->pose * b.grip);
    }
    contacts.update_broad_phase(state.bodies, moving_bodies());
    wake.clear();
    contacts.pressed(state, movers, plate_moves ? held_now : std::vector<int>{}, held_end, wake);
    if (plate_moves) {
      for (const int h : held_now) {
        detail::resting_on(state.bodies, contacts.broad_phase(), h,
                           state.bodies[static_cast<std::size_t>(h)].box.pose, dependents);
        for (const int d : dependents)
          if (!detail::supported(state.bodies, contacts.broad_phase(), d)) wake.push_back(d);
      }
    }
    for (const int i : wake) wake_body(i);
    for (const int i : moving_bodies())
      if (state.bodies[static_cast<std::size_t>(i)].mode == Mode::kAwake) return false;
    if (state.plate) place_held(state.plate->pose, plate_v, plate_w);
    state.time += total;
    stats.steps += n;
    // The belts run up as over fixed steps without a load.
    for (std::size_t k = 0; k < state.belts.size(); ++k) {
      BeltLoad& d = state.belts[k];
      if (drive_speed[k] <= 0.0 || d.speed_fraction >= 1.0) continue;
      d.speed_fraction = std::min(
          1.0, d.speed_fraction + d.max_force / options.belt_inertia * total / drive_speed[k]);
    }
    // The cups' load follows the weight and the plate's acceleration, through
    // the same filter over the call's n fixed steps (nothing else pushes).
    const Eigen::Vector3d gravity(0.0, 0.0, -options.gravity);
    const double keep =
        std::pow(1.0 - std::min(1.0, options.step / kLoadFilter), static_cast<double>(n));
    const double share = pump_share();
    int overloaded = -1;
    double worst = 1.0;
    for (const int h : held_now) {
      Body& b = state.bodies[static_cast<std::size_t>(h)];
      const double need = (b.box.mass * (plate_a - gravity)).norm();
      b.load = need + (b.load - need) * keep;
      const double ratio = b.load / (share * b.capacity);
      if (ratio > worst) {
        worst = ratio;
        overloaded = h;
      }
    }
    if (overloaded >= 0) drop(overloaded, share);
    return true;
  }
  // Fast fidelity, before a step() call: an awake box that is slow (under
  // sleep_speed), touches no robot shape or held box, and rests in balance
  // on the floor and sleeping boxes (the support rule) is at rest: it sleeps
  // at once, without the fixed steps that would find it so. Lowest first,
  // so that a stack at rest sleeps from the floor up in one call.
  void sleep_supported() {
    if (by_id.size() != state.bodies.size()) {
      by_id.clear();
      for (std::size_t i = 0; i < state.bodies.size(); ++i)
        by_id.emplace_back(state.bodies[i].box.id, static_cast<int>(i));
      std::sort(by_id.begin(), by_id.end());
    }
    touches.assign(state.bodies.size(), 0);
    for (const detail::PairState& p : state.pairs) {
      const int a = index_of(p.key.a);
      if (a < 0) continue;
      if (p.key.kind == 1) touches[static_cast<std::size_t>(a)] = 1;
      if (p.key.kind != 0) continue;
      const int b = index_of(p.key.b);
      if (b < 0) continue;
      const auto ka = static_cast<std::size_t>(a), kb = static_cast<std::size_t>(b);
      if (state.bodies[kb].mode == Mode::kHeld) touches[ka] = 1;
      if (state.bodies[ka].mode == Mode::kHeld) touches[kb] = 1;
    }
    calm.clear();
    for (const int i : moving_bodies()) {
      const auto k = static_cast<std::size_t>(i);
      const Body& b = state.bodies[k];
      if (b.mode == Mode::kAwake && touches[k] == 0 &&
          b.v.norm() + b.w.norm() * b.radius < options.sleep_speed)
        calm.push_back(i);
    }
    std::sort(calm.begin(), calm.end(), [&](int x, int y) {
      const double zx = state.bodies[static_cast<std::size_t>(x)].box.pose.translation().z();
      const double zy = state.bodies[static_cast<std::size_t>(y)].box.pose.translation().z();
      return zx < zy || (zx == zy && x < y);
    });
    for (bool slept = !calm.empty(); slept;) {
      slept = false;
      contacts.update_broad_phase(state.bodies, moving_bodies());
      for (const int i : calm) {
        Body& b = state.bodies[static_cast<std::size_t>(i)];
        if (b.mode != Mode::kAwake || !detail::supported(state.bodies, contacts.broad_phase(), i))
          continue;
        b.mode = Mode::kAsleep;
        b.v.setZero();
        b.w.setZero();
        b.still = 0.0;
        rebuild = true;
        moving_stale = true;
        slept = true;
      }
    }
  }
  std::vector<int> calm;                  // sleep_supported()'s scratch
  std::vector<int> held_now, dependents;  // advance_kinematically()'s scratch
  std::vector<Eigen::Isometry3d> held_end;

  // After a fixed step: body i unloaded if it left the trailer or reached
  // the end of a belt (true: it was removed), else put to sleep once it has
  // been slow long enough.
  bool unload_or_sleep(std::size_t i, double dt) {
    Body& b = state.bodies[i];
    if (b.mode == Mode::kHeld || b.mode == Mode::kGone) return false;
    if (b.box.pose.translation().x() < 0.0 || unloaded_by_belt(b)) {
      state.unloaded.push_back({b.box.id, state.time});
      remove(static_cast<int>(i));
      return true;
    }
    if (b.mode != Mode::kAwake || !options.sleeping) return false;
    if (b.still == 0.0) b.rest = b.box.pose;
    // Slow: below sleep_speed, or ringing on its contact springs a little
    // faster while its corners stay within sleep_drift of where it was.
    const double speed = b.v.norm() + b.w.norm() * b.radius;
    const auto drift = [&] {
      const Eigen::AngleAxisd turn(b.box.pose.linear() * b.rest.linear().transpose());
      return (b.box.pose.translation() - b.rest.translation()).norm() +
             std::abs(turn.angle()) * b.radius;
    };
    if (speed < options.sleep_speed ||
        (speed < options.sleep_ring_speed && drift() < options.sleep_drift)) {
      b.still += dt;
      const auto settled = [&] {
        const Wrench& w = wrenches[i];
        const double weight = b.box.mass * options.gravity;
        return speed < options.sleep_speed && drift() < options.sleep_drift &&
               (w.force + Eigen::Vector3d(0.0, 0.0, -weight)).norm() < kBalancedForce * weight &&
               w.torque.norm() < kBalancedArm * weight;
      };
      if (b.still >= options.sleep_time ||
          (b.still >= kBalancedSleepFraction * options.sleep_time && settled())) {
        b.mode = Mode::kAsleep;
        b.v.setZero();
        b.w.setZero();
        rebuild = true;
        moving_stale = true;
      }
    } else {
      b.still = 0.0;
    }
    return false;
  }
};

Simulation::Simulation(const World& world, const PhysicsOptions& options)
    : impl_(std::make_unique<Impl>(world, options)) {}
Simulation::Simulation(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

plr::Expected<Simulation> Simulation::from_snapshot(const Snapshot& snapshot) {
  if (!snapshot.data_) return plr::make_error(PLR_ERR_INVALID, "from_snapshot: empty snapshot");
  return Simulation(std::make_unique<Impl>(*snapshot.data_));
}
Simulation::~Simulation() = default;
Simulation::Simulation(Simulation&&) noexcept = default;
Simulation& Simulation::operator=(Simulation&&) noexcept = default;

void Simulation::step(double duration) {
  Impl& m = *impl_;
  const auto start = std::chrono::steady_clock::now();
  const long n = std::lround(duration / m.options.step);
  if (n <= 0) return;
  const double total = static_cast<double>(n) * m.options.step;
  State& s = m.state;
  // Poses at the start of this call; the targets were set by the caller.
  m.link_paths.clear();
  if (s.links.size() == s.link_targets.size() && !s.links.empty()) {
    for (std::size_t l = 0; l < s.links.size(); ++l)
      m.link_paths.emplace_back(s.links[l].pose, s.link_targets[l].pose, total);
  }
  s.links = s.link_targets;
  m.plate_path.reset();
  Eigen::Vector3d plate_v = Eigen::Vector3d::Zero();
  if (s.plate && s.plate_target) {
    m.plate_path.emplace(s.plate->pose, s.plate_target->pose, total);
    plate_v = (s.plate_target->pose.translation() - s.plate->pose.translation()) / total;
  }
  s.plate = s.plate_target;
  const Eigen::Vector3d plate_a = (plate_v - s.plate_velocity) / total;
  m.prepare_loads();
  m.set_belt_ends();
  m.contacts.set_fast(m.fidelity == Fidelity::kFast);
  if (m.fidelity == Fidelity::kFast) m.sleep_supported();
  // With no box awake, a restored Simbody system integrates nothing.
  if (m.fidelity == Fidelity::kFast && m.pending &&
      std::none_of(s.bodies.begin(), s.bodies.end(),
                   [](const Body& b) { return b.mode == Mode::kAwake; })) {
    m.slots.clear();
    m.pending.reset();
  }
  if (m.fidelity == Fidelity::kFast && !m.pending &&
      m.advance_kinematically(n, total, plate_v, plate_a)) {
    s.plate_velocity = plate_v;
    m.stats.wall_seconds +=
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return;
  }
  std::vector<Eigen::Vector3d> from, to;
  for (std::size_t l = 0; l < s.links.size(); ++l) {
    const bool moves = !m.link_paths.empty();
    from.push_back(moves ? m.link_paths[l].pa : s.links[l].pose.translation());
    to.push_back(moves ? m.link_paths[l].pb : s.links[l].pose.translation());
  }
  m.contacts.sweep_links(s.bodies, from, to);
  for (long k = 0; k < n; ++k) {
    m.fixed_step(m.options.step, static_cast<double>(k) / static_cast<double>(n), plate_a);
  }
  s.plate_velocity = plate_v;
  for (RobotContactForce& f : s.robot_forces) f.mean /= static_cast<double>(n);
  for (BeltLoad& d : s.belts) d.mean_force /= static_cast<double>(n);
  m.stats.wall_seconds +=
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void Simulation::set_fidelity(Fidelity fidelity) {
  impl_->fidelity = fidelity;
}
Fidelity Simulation::fidelity() const {
  return impl_->fidelity;
}

double Simulation::time() const {
  return impl_->state.time;
}

World Simulation::world() const {
  World w;
  w.trailer = impl_->trailer;
  for (const Body& b : impl_->state.bodies) {
    if (b.mode != Mode::kGone) w.boxes.push_back(b.box);
  }
  return w;
}

const Trailer& Simulation::trailer() const {
  return impl_->trailer;
}

void Simulation::set_robot_links(std::vector<LinkGeometry> links) {
  State& s = impl_->state;
  // A new set of shapes appears where it is; a known set moves there in step().
  if (links.size() != s.links.size()) s.links = links;
  impl_->contacts.set_links(links);
  s.link_targets = std::move(links);
}

const std::vector<LinkGeometry>& Simulation::robot_links() const {
  return impl_->state.link_targets;
}

void Simulation::set_suction_plate(const SuctionPlate& plate) {
  State& s = impl_->state;
  if (!s.plate) s.plate = plate;
  s.plate_target = plate;
}

std::vector<std::uint32_t> Simulation::suction_on(const std::vector<bool>& open) {
  Impl& m = *impl_;
  State& s = m.state;
  std::vector<std::uint32_t> gripped;
  if (!s.plate) return gripped;
  // Grip at the pose the plate will have when the next step starts.
  const SuctionPlate& plate = s.plate_target ? *s.plate_target : *s.plate;
  const Eigen::Vector3d z = plate.pose.linear().col(2);
  std::vector<Eigen::Vector3d> cups;
  for (int i = 0; i < plate.cups_x; ++i) {
    for (int j = 0; j < plate.cups_y; ++j) {
      const Eigen::Vector3d local(
          (i + 0.5) / plate.cups_x * plate.extent.x() - 0.5 * plate.extent.x(),
          (j + 0.5) / plate.cups_y * plate.extent.y() - 0.5 * plate.extent.y(), 0.0);
      cups.push_back(plate.pose * local);
    }
  }
  // A closed valve's cup is as good as used.
  std::vector<bool> used(cups.size(), false);
  for (std::size_t c = 0; c < open.size() && c < used.size(); ++c) used[c] = !open[c];
  const double g = m.options.gravity;
  struct Sealed {
    std::size_t body;
    double capacity, load;  // N: its cups at full vacuum, its weight
  };
  std::vector<Sealed> sealed;
  for (std::size_t i = 0; i < s.bodies.size(); ++i) {
    Body& b = s.bodies[i];
    if (b.mode == Mode::kGone || b.mode == Mode::kHeld) continue;
    int covered = 0;
    for (int axis = 0; axis < 3 && covered == 0; ++axis) {
      for (const double side : {-1.0, 1.0}) {
        const Eigen::Vector3d n = side * b.box.pose.linear().col(axis);
        if (n.dot(-z) < std::cos(plate.max_tilt)) continue;
        const Eigen::Vector3d centre = b.box.pose.translation() + n * (0.5 * b.box.size[axis]);
        for (std::size_t c = 0; c < cups.size(); ++c) {
          if (used[c]) continue;
          const double gap = (centre - cups[c]).dot(n) / z.dot(n);
          if (std::abs(gap) > plate.reach) continue;
          const Eigen::Vector3d local = b.box.pose.inverse() * (cups[c] + gap * z);
          bool inside = true;
          for (int k = 0; k < 3; ++k) {
            if (k != axis && std::abs(local[k]) > 0.5 * b.box.size[k] - plate.cup_radius)
              inside = false;
          }
          if (!inside) continue;
          used[c] = true;
          ++covered;
        }
        if (covered > 0) break;
      }
    }
    if (covered == 0) continue;
    sealed.push_back({i, covered * plate.cup_force, b.box.mass * g});
  }
  // The sealed boxes share the pump (pump_share): while one's weight is over
  // its share, the most overloaded one is refused and its cups let go.
  double held = 0.0;  // boxes the plate holds already
  for (const Body& b : s.bodies)
    if (b.mode == Mode::kHeld) held += b.capacity;
  for (;;) {
    double total = held;
    for (const Sealed& x : sealed) total += x.capacity;
    const double share = total > plate.pump_max_force ? plate.pump_max_force / total : 1.0;
    auto worst = sealed.end();
    for (auto it = sealed.begin(); it != sealed.end(); ++it) {
      if (it->load > share * it->capacity &&
          (worst == sealed.end() || it->load / it->capacity > worst->load / worst->capacity))
        worst = it;
    }
    if (worst == sealed.end()) {
      for (const Sealed& x : sealed) {
        Body& b = s.bodies[x.body];
        if (b.mode == Mode::kAwake) m.rebuild = true;
        b.mode = Mode::kHeld;
        m.moving_stale = true;
        b.grip = plate.pose.inverse() * b.box.pose;
        b.capacity = x.capacity;
        b.load = x.load;
        b.v.setZero();
        b.w.setZero();
        s.suction_events.push_back(
            {b.box.id, s.time, SuctionEvent::Kind::kGripped, x.load, share * x.capacity});
        gripped.push_back(b.box.id);
      }
      return gripped;
    }
    s.suction_events.push_back({s.bodies[worst->body].box.id, s.time, SuctionEvent::Kind::kRefused,
                                worst->load, share * worst->capacity});
    sealed.erase(worst);
  }
}

void Simulation::suction_off() {
  Impl& m = *impl_;
  std::vector<std::size_t> released;
  for (std::size_t i = 0; i < m.state.bodies.size(); ++i) {
    Body& b = m.state.bodies[i];
    if (b.mode != Mode::kHeld) continue;
    b.mode = Mode::kAwake;
    b.still = 0.0;
    m.rebuild = true;
    m.moving_stale = true;
    m.state.suction_events.push_back(
        {b.box.id, m.state.time, SuctionEvent::Kind::kReleased, b.load, b.capacity});
    released.push_back(i);
  }
  if (m.fidelity != Fidelity::kFast) return;
  // Boxes let go one above the other are left to the physics: the upper
  // one rides on the lower or falls aside, which the belt rule cannot say.
  const auto footprint = [&](std::size_t i) {
    const Box& b = m.state.bodies[i].box;
    const Eigen::Vector2d e = (b.pose.linear().cwiseAbs() * (0.5 * b.size)).head<2>();
    return std::pair{Eigen::Vector2d(b.pose.translation().head<2>() - e),
                     Eigen::Vector2d(b.pose.translation().head<2>() + e)};
  };
  for (const std::size_t i : released) {
    // A plain pair, not a structured binding: clang 14 cannot capture those.
    const auto box = footprint(i);
    const bool stacked = std::any_of(released.begin(), released.end(), [&](std::size_t j) {
      const auto other = footprint(j);
      return j != i && (box.first.array() < other.second.array()).all() &&
             (other.first.array() < box.second.array()).all();
    });
    if (stacked || !m.over_running_belt(m.state.bodies[i])) continue;
    m.state.unloaded.push_back({m.state.bodies[i].box.id, m.state.time});
    m.remove(static_cast<int>(i));
  }
}

std::vector<std::uint32_t> Simulation::held_boxes() const {
  std::vector<std::uint32_t> ids;
  for (const Body& b : impl_->state.bodies) {
    if (b.mode == Mode::kHeld) ids.push_back(b.box.id);
  }
  return ids;
}

void Simulation::remove_box(std::uint32_t id) {
  for (std::size_t i = 0; i < impl_->state.bodies.size(); ++i) {
    const Body& b = impl_->state.bodies[i];
    if (b.box.id == id && b.mode != Mode::kGone) {
      impl_->remove(static_cast<int>(i));
      return;
    }
  }
  throw std::invalid_argument("remove_box: no box " + std::to_string(id));
}

const std::vector<RobotContactForce>& Simulation::robot_contact_forces() const {
  return impl_->state.robot_forces;
}
const std::vector<BeltLoad>& Simulation::belt_loads() const {
  return impl_->state.belts;
}

const std::vector<UnloadEvent>& Simulation::unloaded() const {
  return impl_->state.unloaded;
}
const std::vector<SuctionEvent>& Simulation::suction_events() const {
  return impl_->state.suction_events;
}

bool Simulation::at_rest() const {
  return std::none_of(impl_->state.bodies.begin(), impl_->state.bodies.end(),
                      [](const Body& b) { return b.mode == Mode::kAwake; });
}

double Simulation::settle(double max_time) {
  const double start = time();
  while (!at_rest()) {
    if (time() - start >= max_time - 1e-9) return -1.0;
    step(std::min(0.01, max_time - (time() - start)));
  }
  return time() - start;
}

Snapshot Simulation::snapshot() const {
  const Impl& m = *impl_;
  auto data = std::make_shared<Snapshot::Data>();
  data->trailer = m.trailer;
  data->options = m.options;
  data->state = m.state;
  State& s = data->state;
  s.rebuild = m.rebuild;
  if (m.pending) {
    s.slots = m.pending->slots;
    s.q = m.pending->q;
    s.u = m.pending->u;
    Snapshot snap;
    snap.data_ = std::move(data);
    return snap;
  }
  s.slots = m.slots;
  std::vector<double> q, u;
  for (std::size_t k = 0; k < m.slots.size(); ++k) {
    m.multibody.coordinates(static_cast<int>(k), q, u);
    s.q.insert(s.q.end(), q.begin(), q.end());
    s.u.insert(s.u.end(), u.begin(), u.end());
  }
  Snapshot snap;
  snap.data_ = std::move(data);
  return snap;
}

void Simulation::restore(const Snapshot& snapshot) {
  if (!snapshot.data_) throw std::invalid_argument("restore: empty snapshot");
  impl_->load(*snapshot.data_);
}

PhysicsStats Simulation::stats() const {
  PhysicsStats s = impl_->stats;
  for (const Body& b : impl_->state.bodies) {
    s.awake += b.mode == Mode::kAwake;
    s.asleep += b.mode == Mode::kAsleep;
    s.held += b.mode == Mode::kHeld;
    s.removed += b.mode == Mode::kGone;
  }
  return s;
}

}  // namespace plr::sim
