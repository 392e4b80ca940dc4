// Actuator limits that depend on absolute mass: a belt's motor force, and
// the push force the robot's shapes feel (the base's limit acts on it).
// The contact model scales with mass, so without such limits scaling every
// mass would change no outcome.
#include <gtest/gtest.h>

#include <cmath>

#include "plr/sim/generators.hpp"
#include "plr/sim/physics.hpp"

namespace plr::sim {
namespace {

constexpr double kSlope = 0.35;  // rad (20 deg), uphill towards the belt's -x end
constexpr double kBeltSpeed = 0.5;

// A belt 2 m long sloping up towards its -x end (where it hands boxes on),
// high enough above the floor that nothing else touches.
LinkGeometry sloped_belt() {
  LinkGeometry belt;
  belt.size = {2.0, 1.0, 0.05};
  belt.pose.linear() = Eigen::AngleAxisd(kSlope, Eigen::Vector3d::UnitY()).toRotationMatrix();
  belt.pose.translation() = Eigen::Vector3d(8.0, 0.0, 0.7);
  belt.belt_speed = kBeltSpeed;
  belt.feeds_belt = true;  // carries boxes up, does not unload them
  return belt;
}

// Four 0.3 m boxes lying on the belt, 0.4 m apart.
World boxes_on(const LinkGeometry& belt, double mass) {
  World w;
  for (int i = 0; i < 4; ++i) {
    Box b;
    b.id = static_cast<std::uint32_t>(i + 1);
    b.size = {0.3, 0.3, 0.3};
    b.mass = mass;
    b.pose = belt.pose * Eigen::Translation3d(0.6 - 0.4 * i, 0.0, 0.025 + 0.15 + 0.001);
    w.boxes.push_back(b);
  }
  return w;
}

struct BeltRun {
  double travel = 0.0;  // m the boxes moved up the belt, mean
  double min_fraction = 1.0;
  double end_fraction = 1.0;
  double peak_force = 0.0;
  int limited_steps = 0;
};

// The boxes settle on the stopped belt, then it runs for 1 s.
BeltRun run_belt(double mass, double max_force = 350.0) {
  LinkGeometry belt = sloped_belt();
  belt.belt_max_force = max_force;
  const World start = boxes_on(belt, mass);
  PhysicsOptions options;
  options.sleeping = false;  // stalled boxes keep their grip on the belt
  Simulation sim(start, options);
  LinkGeometry stopped = belt;
  stopped.belt_speed = 0.0;
  sim.set_robot_links({stopped});
  sim.step(0.3);
  const World settled = sim.world();
  sim.set_robot_links({belt});
  BeltRun r;
  for (int k = 0; k < 100; ++k) {
    sim.step(0.01);
    EXPECT_EQ(sim.belt_loads().size(), 1u);
    const BeltLoad& load = sim.belt_loads()[0];
    r.min_fraction = std::min(r.min_fraction, load.min_speed_fraction);
    r.peak_force = std::max(r.peak_force, load.peak_force);
  }
  r.end_fraction = sim.belt_loads()[0].speed_fraction;
  const Eigen::Vector3d up = -belt.pose.linear().col(0);
  const World end = sim.world();
  EXPECT_EQ(end.boxes.size(), 4u);
  for (std::size_t i = 0; i < end.boxes.size(); ++i) {
    r.travel +=
        0.25 * up.dot(end.boxes[i].pose.translation() - settled.boxes[i].pose.translation());
  }
  r.limited_steps = static_cast<int>(sim.stats().belt_limited_steps);
  return r;
}

// Light boxes (4 x 8 kg: 107 N up the slope, 177 N of friction while they
// catch up) run as if the motor had no limit; three times heavier, catching
// up needs more than the motor's 350 N and the belt slows down before it
// recovers; five times heavier, the slope alone needs 537 N: the belt stalls
// and holds. Without the limit all three would move alike.
TEST(Belt, HeavyLoadsSlowOrStallTheBelt) {
  const BeltRun unlimited = run_belt(40.0, 1e9);
  const BeltRun light = run_belt(8.0);
  const BeltRun heavier = run_belt(24.0);
  const BeltRun heavy = run_belt(40.0);
  EXPECT_GT(unlimited.travel, 0.4);  // 0.5 m/s, less the ~0.2 s the boxes take to catch up
  EXPECT_EQ(light.travel, unlimited.travel);
  EXPECT_EQ(light.min_fraction, 1.0);
  EXPECT_EQ(light.limited_steps, 0);
  EXPECT_LT(light.peak_force, 350.0);

  EXPECT_LT(heavier.min_fraction, 0.9);
  EXPECT_GT(heavier.limited_steps, 0);
  EXPECT_LT(heavier.travel, unlimited.travel - 0.02);
  EXPECT_GT(heavier.travel, 0.5 * unlimited.travel);

  EXPECT_EQ(heavy.end_fraction, 0.0);  // stalled, after 2 cm while it slowed down
  EXPECT_LT(std::abs(heavy.travel), 0.1 * unlimited.travel);
}

TEST(Belt, ShapesOfOneDriveShareItsLimit) {
  // Two 40 kg boxes on each of two belts: a motor each carries its 268 N up
  // the slope; one motor for both shapes stalls under 537 N.
  LinkGeometry a = sloped_belt(), b = sloped_belt();
  a.size.y() = b.size.y() = 0.5;
  a.pose.translation().y() = 0.25;
  b.pose.translation().y() = -0.25;
  World w;
  for (const LinkGeometry* belt : {&a, &b}) {
    for (Box box : boxes_on(*belt, 40.0).boxes) {
      if (box.id > 2) continue;
      box.id += belt == &b ? 10 : 0;
      box.pose.translation().y() = belt->pose.translation().y();
      w.boxes.push_back(box);
    }
  }
  PhysicsOptions options;
  options.sleeping = false;
  for (const int drive_b : {0, 1}) {
    b.belt_drive = drive_b;
    Simulation sim(w, options);
    sim.set_robot_links({a, b});
    double min_fraction = 1.0;
    for (int k = 0; k < 50; ++k) {
      sim.step(0.01);
      for (const BeltLoad& d : sim.belt_loads())
        min_fraction = std::min(min_fraction, d.min_speed_fraction);
    }
    EXPECT_EQ(sim.belt_loads().size(), drive_b == 0 ? 1u : 2u);
    if (drive_b == 0) {
      EXPECT_EQ(min_fraction, 0.0) << "one motor for both";
    } else {
      EXPECT_GT(min_fraction, 0.3) << "a motor each";
    }
  }
}

Box floor_box(std::uint32_t id, const Eigen::Vector3d& size, const Eigen::Vector2d& xy, double z,
              double mass) {
  Box b;
  b.id = id;
  b.size = size;
  b.mass = mass;
  b.pose.translation() = Eigen::Vector3d(xy.x(), xy.y(), z + 0.5 * size.z());
  return b;
}

// Drives a 1.2 m wide paddle (the base's front) at 0.2 m/s along +x for
// `seconds`; returns the mean force on it over the last half.
Eigen::Vector3d push(Simulation& sim, double from_x, double seconds) {
  LinkGeometry paddle;
  paddle.size = {0.3, 1.2, 0.5};
  const int steps = static_cast<int>(std::lround(seconds / 0.01));
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (int k = 0; k <= steps; ++k) {
    paddle.pose.translation() = Eigen::Vector3d(from_x + 0.002 * k, 0.0, 0.26);
    sim.set_robot_links({paddle});
    sim.step(0.01);
    EXPECT_EQ(sim.robot_contact_forces().size(), 1u);
    const RobotContactForce& f = sim.robot_contact_forces()[0];
    EXPECT_LE(f.mean.norm(), f.peak.norm() + 1e-9);
    if (k > steps / 2) mean += f.mean / (steps - steps / 2);
  }
  return mean;
}

TEST(PushForce, ASlidingBoxResistsWithItsFloorFriction) {
  World w;
  w.boxes.push_back(floor_box(1, {0.4, 0.4, 0.4}, {10.0, 0.0}, 0.0, 10.0));
  Simulation sim(w);
  const Eigen::Vector3d f = push(sim, 10.0 - 0.2 - 0.15 - 0.05, 1.5);
  // Coulomb on the floor, 0.4 x the normal force: the box's weight less
  // what the paddle's friction carries (the box leans on it a little).
  EXPECT_LT(f.z(), 0.0);
  EXPECT_NEAR(-f.x(), 0.4 * (10.0 * 9.81 + f.z()), 0.01 * 39.24);
  EXPECT_NEAR(-f.x(), 0.4 * 10.0 * 9.81, 0.1 * 39.24);
  EXPECT_LT(std::abs(f.y()), 0.1);
}

// Two settled piles of the same geometry, one five times heavier: pushing
// them the same way takes five times the force (the geometry and motion are
// the same, as the contact model scales with mass; the force does not).
TEST(PushForce, GrowsWithTheMassOfWhatIsPushed) {
  World light = generate_world(EnvFamily::kB1, 11);
  light.boxes.resize(40);
  double front = 1e9;
  for (const Box& b : light.boxes) {
    const Eigen::Vector3d e = b.pose.linear().cwiseAbs() * (0.5 * b.size);
    front = std::min(front, b.pose.translation().x() - e.x());
  }
  World heavy = light;
  for (Box& b : heavy.boxes) b.mass *= 5.0;
  Simulation a(light), b(heavy);
  ASSERT_GE(a.settle(3.0), 0.0);
  ASSERT_GE(b.settle(3.0), 0.0);
  const double fa = -push(a, front - 0.15 - 0.05, 2.0).x();
  const double fb = -push(b, front - 0.15 - 0.05, 2.0).x();
  EXPECT_GT(fa, 20.0);  // it did push the pile
  EXPECT_NEAR(fb / fa, 5.0, 0.25);
}

}  // namespace
}  // namespace plr::sim
