// Rigid-body simulation of the boxes in the trailer (the true state W^t).
//
// Boxes are free bodies with gravity, penalty contact and friction among
// themselves, with the trailer (floor, side walls, ceiling, front wall; the
// rear is open) and with robot shapes. Robot shapes are kinematic: they follow
// the poses they are given whatever the boxes do. Simbody integrates the
// boxes that move; boxes at rest sleep (cost nothing) until something moving
// touches them, so cost follows the active region. Same world, same options
// and same calls give bit-identical results on one machine.
//
// Simbody types stay behind the pimpl: this header is plain C++17 + Eigen.
#pragma once

#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "plr/expected.hpp"
#include "plr/sim/fidelity.hpp"
#include "plr/sim/generators.hpp"
#include "plr/sim/suction_plate.hpp"
#include "plr/sim/world.hpp"

namespace plr::sim {

// One kinematic robot shape (a link's collision geometry), world frame.
struct LinkGeometry {
  enum class Shape { kBox, kCylinder };
  Shape shape = Shape::kBox;
  // Box: full extents. Cylinder: x = radius, z = length along its local z axis.
  Eigen::Vector3d size{0.1, 0.1, 0.1};
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  // Conveyor belt on this shape: its surface moves along the shape's local -x
  // axis at this speed (m/s). A box lying on it whose trailing edge reaches
  // the local -x end is handed to the robot's body conveyor and counts as
  // unloaded, unless that end feeds another belt (`feeds_belt`).
  double belt_speed = 0.0;
  bool feeds_belt = false;
  // The motor behind the belt. Shapes with the same `belt_drive` are one
  // belt: the tangential forces their surfaces exert on boxes add up, and
  // when the sum exceeds `belt_max_force` (the first such shape's) the
  // surface slows down, to a stall if need be; a lighter load lets it run
  // up to belt_speed again. Default: a 0.37 kW gear motor section (see
  // docs/notes-sim.md).
  int belt_drive = 0;
  double belt_max_force = 350.0;  // N
};

struct PhysicsOptions {
  double step = 5e-4;  // s; fixed
  double gravity = 9.81;
  double friction_box = 0.5;  // Coulomb coefficients
  double friction_trailer = 0.4;
  double friction_robot = 0.6;
  // Penalty contact: a pair's stiffness is reduced_mass * contact_omega^2, so
  // light and heavy boxes ring at the same frequency (stable at this step).
  double contact_omega = 600.0;  // rad/s
  double damping_ratio = 0.5;    // contacts with robot shapes (explicit damper)
  // Box-box and box-trailer contacts: cardboard does not bounce, and a stack
  // must not rock on its contact springs. Damped implicitly, so any value is
  // stable; normal c = 2 * ratio * mass * contact_omega, tangential half, with
  // the larger of the pair's reduced mass and the mass the contact carries
  // (its spring force / gravity).
  double box_damping_ratio = 4.0;
  bool sleeping = true;
  double sleep_speed = 0.01;  // m/s at the box's corners
  // s slow before a box freezes; a fifth of it for one that also stays
  // within sleep_drift and in balance (contact force within 5 % of its
  // weight, torque under its weight x 2 mm): most wakes do not disturb a box.
  double sleep_time = 0.25;
  // Also slow: up to sleep_ring_speed while the corners stay within
  // sleep_drift of where they were when the box became slow: a box ringing on
  // its contact springs. One really moving at sleep_speed or more leaves that
  // behind within 0.1 s, well before sleep_time.
  double sleep_ring_speed = 0.03;  // m/s
  double sleep_drift = 0.001;      // m
  double wake_speed = 0.05;        // m/s of a box touching a sleeping one that wakes it
  double wake_depth = 0.003;       // m of penetration by something slower that wakes a box
  // Inertia of a belt drive reflected to the belt surface (rotor through the
  // gearbox, drums, belt): how fast a belt over its force limit slows down
  // and an unloaded one runs up again.
  double belt_inertia = 100.0;  // kg
};

struct UnloadEvent {
  std::uint32_t box_id = 0;
  double time = 0.0;
};

struct SuctionEvent {
  enum class Kind { kGripped, kRefused, kDropped, kReleased };
  std::uint32_t box_id = 0;
  double time = 0.0;
  Kind kind = Kind::kGripped;
  double load = 0.0;      // N the cups had to hold
  double capacity = 0.0;  // N they could hold
};

// A belt drive (LinkGeometry::belt_drive) over the last step() call.
struct BeltLoad {
  int drive = 0;
  double max_force = 0.0;       // N
  double speed_fraction = 1.0;  // of belt_speed, at the end of the call
  double min_speed_fraction = 1.0;
  // Force the belt surfaces exerted on the boxes along their motion (the
  // motor's load), N: mean and largest over the call's fixed steps.
  double mean_force = 0.0;
  double peak_force = 0.0;
};

// What the boxes pushed on one robot shape (normal and friction forces of
// every contact), world frame, N, over the last step() call: the mean over
// its fixed steps and the fixed step's force of largest norm. Sleeping boxes
// push on nothing that stands still.
struct RobotContactForce {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  Eigen::Vector3d peak = Eigen::Vector3d::Zero();
};

struct PhysicsStats {
  std::int64_t steps = 0;               // fixed steps taken
  std::int64_t dynamic_steps = 0;       // steps that ran Simbody (some box awake)
  std::int64_t body_steps = 0;          // sum over steps of awake boxes
  std::int64_t rebuilds = 0;            // Simbody systems built for a new awake set
  std::int64_t belt_limited_steps = 0;  // steps with a running belt below its speed
  std::int64_t diverged = 0;            // boxes stopped by the divergence guard
  std::int64_t frozen = 0;              // boxes put to sleep by the adaptive rule
  double wall_seconds = 0.0;            // time spent in step()
  int awake = 0, asleep = 0, held = 0, removed = 0;
};

// A simulation's full state: the trailer, the options and everything that
// moves, including Simbody's exact coordinates of the moving boxes. A copy
// shares the (immutable) data.
class Snapshot {
 public:
  Snapshot();
  ~Snapshot();
  Snapshot(const Snapshot&);
  Snapshot& operator=(const Snapshot&);
  bool empty() const;
  double time() const;
  // Boxes still in the trailer (as Simulation::world() at the snapshot).
  World world() const;
  const PhysicsOptions& options() const;

  // FlatBuffers bytes of sdk/schemas/sim_state.fbs (SimulationState, file
  // identifier "PSIM"); empty for an empty snapshot. The bytes restore the
  // exact doubles, so a run continued from them in another process repeats
  // the original bit for bit (same binary and machine).
  std::vector<std::uint8_t> to_bytes() const;
  // Untrusted bytes: verified, every count bounded, every number checked
  // (finite, in range, rotations orthonormal, consistent counts); the first
  // problem is a one-line error naming the field, e.g.
  // "sim state: bodies[3].mass: must be finite and > 0".
  static plr::Expected<Snapshot> from_bytes(const std::uint8_t* data, std::size_t size);

 private:
  friend class Simulation;
  struct Data;
  std::shared_ptr<const Data> data_;
};

class Simulation {
 public:
  explicit Simulation(const World& world, const PhysicsOptions& options = {});
  // A simulation that continues the snapshot's (its world, options and
  // state) exactly as the one it was taken from would; an empty snapshot is
  // refused.
  static plr::Expected<Simulation> from_snapshot(const Snapshot& snapshot);
  ~Simulation();
  Simulation(Simulation&&) noexcept;
  Simulation& operator=(Simulation&&) noexcept;

  // How accurately the boxes are simulated from the next step on (default
  // full). Not part of the state: restore() and snapshots leave it alone.
  void set_fidelity(Fidelity fidelity);
  Fidelity fidelity() const;

  // Advances by `duration` (rounded to whole steps). Robot shapes and the
  // suction plate move from their previous poses to the last ones set,
  // linearly over this call.
  void step(double duration);
  double time() const;

  // Current true state: boxes still in the trailer (held ones included), with
  // masses. Unloaded and removed boxes are gone.
  World world() const;
  const Trailer& trailer() const;

  // Target poses for the next step(); same count and order as before to move
  // smoothly, otherwise the shapes are replaced at once (no velocity).
  void set_robot_links(std::vector<LinkGeometry> links);
  const std::vector<LinkGeometry>& robot_links() const;

  void set_suction_plate(const SuctionPlate& plate);
  // Grips every box facing the plate within reach that the covering cups can
  // hold (load = mass * g); boxes too heavy are refused. The sealed cups of
  // all held boxes share the pump (SuctionPlate::pump_max_force): each box
  // holds its cups' share, and while a box is over its share the most
  // overloaded one is refused (here) or dropped (while held, by the load of
  // mass * (g + acceleration) and what its neighbours push), one at a time.
  // `open`: the plate's valves, one per cup (SuctionPlate's order: row by
  // row up the plate, across each row); a closed cup seals on nothing. Empty:
  // all open. Returns the ids gripped.
  std::vector<std::uint32_t> suction_on(const std::vector<bool>& open = {});
  void suction_off();
  std::vector<std::uint32_t> held_boxes() const;

  // Takes a box out by hand (not counted as unloaded); what touched it wakes.
  void remove_box(std::uint32_t id);

  // One per shape of the last step() call, in robot_links() order.
  const std::vector<RobotContactForce>& robot_contact_forces() const;
  // Belt drives met so far, by drive id.
  const std::vector<BeltLoad>& belt_loads() const;

  const std::vector<UnloadEvent>& unloaded() const;
  const std::vector<SuctionEvent>& suction_events() const;

  // True when no box moves (all asleep, or held).
  bool at_rest() const;
  // Steps until at rest or `max_time` more seconds passed; returns the time it
  // took, or a negative value if the boxes still move.
  double settle(double max_time);

  // A snapshot is a copy of the plain state plus Simbody's coordinates of
  // the moving boxes; restore copies it back (trailer and options too, so
  // any snapshot will do) and rebuilds Simbody's system lazily at the next
  // step. Restored runs repeat bit for bit. Work counters (stats()) are not
  // part of the state.
  Snapshot snapshot() const;
  void restore(const Snapshot& snapshot);

  PhysicsStats stats() const;

 private:
  struct Impl;
  explicit Simulation(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// generate_world, then let the boxes fall and come to rest (at most
// `max_settle` simulated seconds): piles tumble into shape, walls sink into
// their contact equilibrium (tenths of a millimetre).
World make_environment(EnvFamily family, std::uint64_t seed, const Trailer& trailer = {},
                       double max_settle = 6.0);

}  // namespace plr::sim
