// Suction gripping, holding by load, and the conveyor.
#include <gtest/gtest.h>

#include <algorithm>

#include "plr/sim/generators.hpp"
#include "plr/sim/physics.hpp"

namespace plr::sim {
namespace {

World one_box(double mass) {
  World w;
  Box b;
  b.id = 1;
  b.size = {0.4, 0.4, 0.4};
  b.pose.translation() = Eigen::Vector3d(10.0, 0.0, 0.2);
  b.mass = mass;
  w.boxes.push_back(b);
  return w;
}

// Cup face on the box's top face, pointing down. 4 x 3 cups over 0.6 x 0.4 m:
// six of them seal on a 0.4 m box (capacity 6 * 45 N = 270 N).
SuctionPlate plate_at(double z) {
  SuctionPlate p;
  p.extent = {0.6, 0.4};
  p.cups_x = 4;
  p.cups_y = 3;
  p.cup_force = 45.0;
  p.pose = Eigen::Translation3d(10.0, 0.0, z) * Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX());
  return p;
}

// Lifts the plate with constant acceleration `a` until `height` above the start.
void lift(Simulation& sim, double a, double height) {
  double z = 0.4, v = 0.0;
  const double dt = 0.01;
  while (z < 0.4 + height) {
    v += a * dt;
    z += v * dt;
    sim.set_suction_plate(plate_at(z));
    sim.step(dt);
  }
}

TEST(Suction, LiftsAFiveKilogramBox) {
  Simulation sim(one_box(5.0));
  ASSERT_GE(sim.settle(1.0), 0.0);
  sim.set_suction_plate(plate_at(0.4));
  EXPECT_EQ(sim.suction_on(), std::vector<std::uint32_t>{1});
  lift(sim, 2.0, 0.5);
  sim.step(0.5);  // hold still in the air
  ASSERT_EQ(sim.held_boxes(), std::vector<std::uint32_t>{1});
  EXPECT_GT(sim.world().boxes[0].pose.translation().z(), 0.68);
  const SuctionEvent& e = sim.suction_events().front();
  EXPECT_EQ(e.kind, SuctionEvent::Kind::kGripped);
  EXPECT_NEAR(e.capacity, 270.0, 1e-9);
  // Released, it falls back to the floor.
  sim.suction_off();
  EXPECT_GE(sim.settle(2.0), 0.0);
  EXPECT_NEAR(sim.world().boxes[0].pose.translation().z(), 0.2, 0.004);
}

TEST(Suction, RefusesABoxOverCapacity) {
  Simulation sim(one_box(30.0));  // 294 N > 270 N
  sim.set_suction_plate(plate_at(0.4));
  EXPECT_TRUE(sim.suction_on().empty());
  ASSERT_EQ(sim.suction_events().size(), 1u);
  EXPECT_EQ(sim.suction_events()[0].kind, SuctionEvent::Kind::kRefused);
  lift(sim, 2.0, 0.3);
  EXPECT_NEAR(sim.world().boxes[0].pose.translation().z(), 0.2, 0.004);  // not lifted
}

TEST(Suction, DropsABoxWhenAccelerationOverloadsTheCups) {
  Simulation sim(one_box(20.0));  // 196 N at rest, 276 N at 4 m/s^2 upwards
  sim.set_suction_plate(plate_at(0.4));
  ASSERT_EQ(sim.suction_on().size(), 1u);
  lift(sim, 4.0, 0.4);
  ASSERT_FALSE(sim.suction_events().empty());
  EXPECT_EQ(sim.suction_events().back().kind, SuctionEvent::Kind::kDropped);
  EXPECT_TRUE(sim.held_boxes().empty());
  EXPECT_GE(sim.settle(2.0), 0.0);
  EXPECT_NEAR(sim.world().boxes[0].pose.translation().z(), 0.2, 0.01);
}

TEST(Suction, ACupOverTheEdgeDoesNotSeal) {
  // Shifted 6 cm along y, one row of cups has its centre 0.193 m from the
  // box's centre: on the face, but its rim is not. Two rows of two seal.
  Simulation sim(one_box(5.0));
  SuctionPlate p = plate_at(0.4);
  p.pose.translation().y() += 0.06;
  sim.set_suction_plate(p);
  EXPECT_EQ(sim.suction_on(), std::vector<std::uint32_t>{1});
  EXPECT_NEAR(sim.suction_events().back().capacity, 4 * 45.0, 1e-9);
}

TEST(Suction, MissesABoxOutOfReach) {
  Simulation sim(one_box(5.0));
  sim.set_suction_plate(plate_at(0.45));  // 5 cm above the top face
  EXPECT_TRUE(sim.suction_on().empty());
  EXPECT_TRUE(sim.suction_events().empty());
}

// Two 0.4 m boxes side by side on the floor, 1 cm apart (ids 1 and 2, y > 0
// and y < 0), with the masses given.
World two_boxes(double mass) {
  World w;
  for (std::uint32_t id : {1u, 2u}) {
    Box b;
    b.id = id;
    b.size = {0.4, 0.4, 0.4};
    b.pose.translation() = Eigen::Vector3d(10.0, id == 1 ? 0.205 : -0.205, 0.2);
    b.mass = mass;
    w.boxes.push_back(b);
  }
  return w;
}

// The robot's plate (the default grid: 4 x 5 cups over 0.4 x 0.5 m) over
// the seam between the two boxes, pointing down: two columns of four cups
// seal on each, 8 * 90 = 720 N on either alone. Together their sixteen cups
// share the pump's 1080 N: 540 N each.
SuctionPlate robot_plate_at(double z) {
  SuctionPlate p;
  p.pose = Eigen::Translation3d(10.0, 0.0, z) * Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX());
  return p;
}

void lift_robot_plate(Simulation& sim, double a, double height) {
  double z = 0.4, v = 0.0;
  const double dt = 0.01;
  while (z < 0.4 + height) {
    v += a * dt;
    z += v * dt;
    sim.set_suction_plate(robot_plate_at(z));
    sim.step(dt);
  }
  sim.step(0.3);  // and hold it there
}

TEST(Suction, SeveralBoxesAtOnceHoldWhenLightAndDropWhenHeavy) {
  // Light: 8 kg each, 111 N at 4 m/s^2 upwards against 540 N each.
  {
    Simulation sim(two_boxes(8.0));
    sim.set_suction_plate(robot_plate_at(0.4));
    ASSERT_EQ(sim.suction_on().size(), 2u);
    for (const SuctionEvent& e : sim.suction_events()) EXPECT_NEAR(e.capacity, 540.0, 1e-9);
    lift_robot_plate(sim, 4.0, 0.4);
    EXPECT_EQ(sim.held_boxes().size(), 2u);
    for (const Box& b : sim.world().boxes) EXPECT_GT(b.pose.translation().z(), 0.55);
  }
  // The same boxes at 45 kg: 441 N at rest is held, 621 N while lifted is
  // not. The first to let go leaves the other all its cups' force (720 N).
  World heavy = two_boxes(8.0);
  ASSERT_TRUE(set_masses(heavy, {{1, 45.0}, {2, 45.0}}));
  Simulation sim(heavy);
  sim.set_suction_plate(robot_plate_at(0.4));
  ASSERT_EQ(sim.suction_on().size(), 2u);
  lift_robot_plate(sim, 4.0, 0.4);
  std::vector<SuctionEvent> drops;
  for (const SuctionEvent& e : sim.suction_events())
    if (e.kind == SuctionEvent::Kind::kDropped) drops.push_back(e);
  ASSERT_FALSE(drops.empty());
  EXPECT_LT(sim.held_boxes().size(), 2u);
  EXPECT_EQ(drops.size() + sim.held_boxes().size(), 2u);  // one event per box dropped
  for (const SuctionEvent& e : drops) {
    EXPECT_GT(e.load, e.capacity);
    EXPECT_NEAR(e.capacity, 540.0, 1e-9);
  }
  // What dropped fell back to the floor.
  sim.step(1.0);
  for (const Box& b : sim.world().boxes) {
    const auto held = sim.held_boxes();
    if (std::find(held.begin(), held.end(), b.id) == held.end()) {
      EXPECT_NEAR(b.pose.translation().z(), 0.2, 0.02) << "box " << b.id;
    }
  }
}

// The plate's valves: over the seam, with only the cups on box 1's side open
// (local y < 0: the plate faces down, turned about x), box 2 is not taken.
TEST(Suction, ClosedCupsSealOnNothing) {
  Simulation sim(two_boxes(8.0));
  const SuctionPlate plate = robot_plate_at(0.4);
  sim.set_suction_plate(plate);
  std::vector<bool> open;
  for (int row = 0; row < plate.cups_x; ++row)
    for (int col = 0; col < plate.cups_y; ++col) open.push_back(col < plate.cups_y / 2);
  EXPECT_EQ(sim.suction_on(open), std::vector<std::uint32_t>{1});
  // Its two columns of four cups, at full vacuum.
  EXPECT_NEAR(sim.suction_events().front().capacity, 720.0, 1e-9);
  lift_robot_plate(sim, 2.0, 0.3);
  EXPECT_EQ(sim.held_boxes(), std::vector<std::uint32_t>{1});
}

TEST(Suction, ThePumpHoldsEachBoxAloneButNotBothTogether) {
  // 60 kg, 589 N: under the 720 N one box's eight cups hold alone, over the
  // 540 N each holds when both share the pump.
  for (std::uint32_t id : {1u, 2u}) {
    World w = two_boxes(60.0);
    w.boxes.erase(w.boxes.begin() + (id == 1 ? 1 : 0));
    Simulation sim(w);
    sim.set_suction_plate(robot_plate_at(0.4));
    EXPECT_EQ(sim.suction_on(), std::vector<std::uint32_t>{id});
    EXPECT_NEAR(sim.suction_events().back().capacity, 720.0, 1e-9);
  }
  Simulation sim(two_boxes(60.0));
  sim.set_suction_plate(robot_plate_at(0.4));
  EXPECT_EQ(sim.suction_on().size(), 1u);
  ASSERT_EQ(sim.suction_events().size(), 2u);
  const SuctionEvent& refused = sim.suction_events()[0];
  EXPECT_EQ(refused.kind, SuctionEvent::Kind::kRefused);
  EXPECT_NEAR(refused.load, 60.0 * 9.81, 1e-9);
  EXPECT_NEAR(refused.capacity, 540.0, 1e-9);
  // The other, alone on the pump, holds with all of it.
  EXPECT_EQ(sim.suction_events()[1].kind, SuctionEvent::Kind::kGripped);
  EXPECT_NEAR(sim.suction_events()[1].capacity, 720.0, 1e-9);
}

// A 2 m belt lying at x 2..4, its centre at height z, running towards the rear.
LinkGeometry belt(double z, double speed) {
  LinkGeometry b;
  b.size = {2.0, 0.8, 0.1};
  b.pose.translation() = Eigen::Vector3d(3.0, 0.0, z);
  b.belt_speed = speed;
  return b;
}

TEST(Conveyor, CarriesABoxOutAndCountsIt) {
  World w = one_box(6.0);
  w.boxes[0].pose.translation() = Eigen::Vector3d(3.0, 0.0, 0.5 + 0.2 + 0.002);
  Simulation sim(w);
  sim.set_robot_links({belt(0.45, 0.8)});  // its surface at z = 0.5
  sim.step(0.5);
  ASSERT_EQ(sim.world().boxes.size(), 1u);
  EXPECT_LT(sim.world().boxes[0].pose.translation().x(), 2.9);  // moving with the belt
  sim.step(2.0);
  ASSERT_EQ(sim.unloaded().size(), 1u);
  EXPECT_EQ(sim.unloaded()[0].box_id, 1u);
  EXPECT_GT(sim.unloaded()[0].time, 1.0);
  EXPECT_LT(sim.unloaded()[0].time, 2.5);
  EXPECT_TRUE(sim.world().boxes.empty());
}

TEST(Conveyor, StoppedBeltHoldsTheBox) {
  World w = one_box(6.0);
  w.boxes[0].pose.translation() = Eigen::Vector3d(3.0, 0.0, 0.5 + 0.2 + 0.002);
  Simulation sim(w);
  sim.set_robot_links({belt(0.45, 0.0)});
  sim.step(2.0);
  ASSERT_EQ(sim.world().boxes.size(), 1u);
  EXPECT_NEAR(sim.world().boxes[0].pose.translation().x(), 3.0, 0.005);
  EXPECT_TRUE(sim.unloaded().empty());
}

TEST(Conveyor, ABoxOnTheFloorAtTheBeltsEndIsNotOnTheBelt) {
  // A low running belt (top 0.1 m) ending at x = 2; a 0.4 m box stands on the
  // floor just behind that end, its centre above the belt's mid-plane. It has
  // not reached the body conveyor: only a box lying on the belt has.
  World w = one_box(6.0);
  w.boxes[0].pose.translation() = Eigen::Vector3d(2.0 - 0.21, 0.0, 0.2);
  Simulation sim(w);
  sim.set_robot_links({belt(0.05, 0.8)});
  sim.step(0.5);
  EXPECT_TRUE(sim.unloaded().empty());
  ASSERT_EQ(sim.world().boxes.size(), 1u);
}

TEST(Conveyor, BoxLeavingThroughTheRearIsUnloaded) {
  World w = one_box(6.0);
  w.boxes[0].pose.translation() = Eigen::Vector3d(0.5, 0.0, 0.2);
  Simulation sim(w);
  LinkGeometry pusher;
  pusher.size = {0.1, 0.4, 0.3};
  for (int k = 0; k <= 100; ++k) {
    pusher.pose.translation() = Eigen::Vector3d(0.76 - 0.01 * k, 0.0, 0.2);
    sim.set_robot_links({pusher});
    sim.step(0.01);
  }
  ASSERT_EQ(sim.unloaded().size(), 1u);
  EXPECT_TRUE(sim.world().boxes.empty());
}

}  // namespace
}  // namespace plr::sim
