// Fidelity levels: full is the simulation as it was; adaptive freezes boxes
// with no contact path to the action and wakes them when the action comes
// near; fast moves the robot kinematically and simulates only the boxes it
// presses into or that lose their support.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "paddle_through_pile.hpp"
#include "plr/sim/fidelity.hpp"
#include "plr/sim/generators.hpp"
#include "plr/sim/physics.hpp"

namespace plr::sim {
namespace {

Box cube(std::uint32_t id, Eigen::Vector3d centre, double mass = 8.0) {
  Box b;
  b.id = id;
  b.size = {0.4, 0.4, 0.4};
  b.pose.translation() = centre;
  b.mass = mass;
  return b;
}

// A paddle driven through the pile, then the pile left to settle.
void sweep(Simulation& sim) {
  test::drive_paddle(sim);
  sim.set_robot_links({});
  sim.step(0.5);
}

TEST(Fidelity, ParsesTheThreeLevelsAndRefusesTheOthers) {
  EXPECT_EQ(*parse_fidelity("full"), Fidelity::kFull);
  EXPECT_EQ(*parse_fidelity("adaptive"), Fidelity::kAdaptive);
  EXPECT_EQ(*parse_fidelity("fast"), Fidelity::kFast);
  const auto other = parse_fidelity("medium");
  ASSERT_FALSE(other);
  EXPECT_NE(other.error().message.find("'medium'"), std::string::npos);
  EXPECT_EQ(to_string(Fidelity::kAdaptive), "adaptive");
  EXPECT_EQ(to_string(Fidelity::kFast), "fast");
}

// Full fidelity is the default, and a simulation set to full after running
// adaptive continues a snapshot exactly as one that never did: the level is
// a setting, nothing of it enters the state.
TEST(Fidelity, FullIsTheDefaultAndLeavesNoTraceInTheState) {
  Simulation plain(test::small_pile());
  EXPECT_EQ(plain.fidelity(), Fidelity::kFull);
  plain.step(0.4);
  const Snapshot start = plain.snapshot();
  sweep(plain);
  EXPECT_EQ(plain.stats().frozen, 0);

  Simulation switched(test::small_pile());
  switched.set_fidelity(Fidelity::kAdaptive);
  switched.step(0.4);
  sweep(switched);
  EXPECT_GT(switched.stats().frozen, 0);
  switched.set_fidelity(Fidelity::kFull);
  switched.restore(start);
  EXPECT_EQ(switched.fidelity(), Fidelity::kFull);
  sweep(switched);
  EXPECT_EQ(plain.snapshot().to_bytes(), switched.snapshot().to_bytes());
}

// Adaptive runs are decided by the state alone: a restored run repeats.
TEST(Fidelity, AdaptiveRestoredRunRepeatsBitForBit) {
  Simulation sim(test::small_pile());
  sim.set_fidelity(Fidelity::kAdaptive);
  sim.step(0.4);
  const Snapshot start = sim.snapshot();
  sweep(sim);
  const std::vector<std::uint8_t> first = sim.snapshot().to_bytes();
  sim.restore(start);
  EXPECT_EQ(sim.fidelity(), Fidelity::kAdaptive);
  sweep(sim);
  EXPECT_EQ(first, sim.snapshot().to_bytes());
}

// A pile falling into shape, no robot: groups of boxes that touch nothing
// moving fast freeze as soon as they are slow, before they are balanced;
// fewer box-steps are integrated and the boxes come to rest near where they
// do at full fidelity.
TEST(Fidelity, AdaptiveFreezesSlowGroupsAwayFromTheAction) {
  Simulation full(test::small_pile()), adaptive(test::small_pile());
  adaptive.set_fidelity(Fidelity::kAdaptive);
  full.step(0.4);
  adaptive.step(0.4);
  EXPECT_EQ(full.stats().frozen, 0);
  EXPECT_GT(adaptive.stats().frozen, 0);
  EXPECT_LT(adaptive.stats().body_steps, full.stats().body_steps);
  const World a = adaptive.world(), f = full.world();
  ASSERT_EQ(a.boxes.size(), f.boxes.size());
  for (std::size_t i = 0; i < a.boxes.size(); ++i) {
    EXPECT_LT((a.boxes[i].pose.translation() - f.boxes[i].pose.translation()).norm(), 0.05)
        << "box " << a.boxes[i].id;
  }
}

// Box 2 is pushed slowly (under wake_speed) towards box 1, which has been
// asleep (frozen). Returns the gap between them (m) when box 1 woke.
double gap_when_woken(Fidelity fidelity) {
  World w;
  w.boxes.push_back(cube(1, {10.6, 0.0, 0.2}));
  w.boxes.push_back(cube(2, {10.0, 0.0, 0.2}));
  Simulation sim(w);
  sim.set_fidelity(fidelity);
  EXPECT_GE(sim.settle(2.0), 0.0);
  EXPECT_EQ(sim.stats().asleep, 2);
  LinkGeometry pusher;
  pusher.size = {0.1, 0.3, 0.2};
  const double speed = 0.04;  // m/s, under wake_speed (0.05)
  for (int k = 0; k <= 1200; ++k) {
    pusher.pose.translation() = Eigen::Vector3d(9.75 + speed * 0.01 * k, 0.0, 0.15);
    sim.set_robot_links({pusher});
    sim.step(0.01);
    const World now = sim.world();
    const double gap =
        now.boxes[0].pose.translation().x() - now.boxes[1].pose.translation().x() - 0.4;
    if (sim.stats().asleep == 0) return gap;  // both awake
  }
  ADD_FAILURE() << "box 1 never woke";
  return 1.0;
}

TEST(Fidelity, FrozenBoxWakesWhenAPushedBoxComesWithinTheMargin) {
  const double adaptive_gap = gap_when_woken(Fidelity::kAdaptive);
  // Woken before the boxes touch, within the wake margin (1 cm) and a
  // control period's travel.
  EXPECT_GT(adaptive_gap, 0.0);
  EXPECT_LT(adaptive_gap, 0.01 + 0.04 * 0.01 + 1e-4);
  // At full fidelity a box this slow wakes it only by pressing into it.
  const double full_gap = gap_when_woken(Fidelity::kFull);
  EXPECT_LT(full_gap, 0.0);
}

// Fast fidelity: a box pulled out from under another without pressing into
// it (straight back, no lift) leaves it with nothing to rest on; the support
// rule hands it to the physics and it falls to the floor, as at full
// fidelity. Without the rule nothing touches it and it would stay in the air.
TEST(Fidelity, FastDropsABoxWhoseSupportIsPulledAway) {
  for (const Fidelity level : {Fidelity::kFull, Fidelity::kFast}) {
    World w;
    w.boxes = {cube(1, {1.0, 0.0, 0.2}), cube(2, {1.0, 0.0, 0.6})};
    Simulation sim(w);
    ASSERT_GE(sim.settle(1.0), 0.0);
    sim.set_fidelity(level);
    // Four cups on the lower box's face towards the rear, none on the
    // upper's, strong enough to jerk it out at once: the upper box's
    // friction cannot take it along.
    SuctionPlate plate;
    plate.extent = {0.2, 0.2};
    plate.cups_x = 2;
    plate.cups_y = 2;
    plate.cup_force = 2000.0;
    plate.pump_max_force = 1e5;
    const auto at = [&](double x) {
      plate.pose =
          Eigen::Translation3d(x, 0.0, 0.2) * Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitY());
      return plate;
    };
    sim.set_suction_plate(at(0.8));
    ASSERT_EQ(sim.suction_on(), std::vector<std::uint32_t>{1});
    for (int k = 1; k <= 50; ++k) {  // 1 m back at 2 m/s
      sim.set_suction_plate(at(0.8 - 0.02 * k));
      sim.step(0.01);
    }
    sim.step(1.0);
    double z = 0.0;
    for (const Box& b : sim.world().boxes)
      if (b.id == 2) z = b.pose.translation().z();
    EXPECT_LT(z, 0.25) << to_string(level);
  }
}

// Fast fidelity is deterministic: the same state and calls give the same
// state, to the bit, whether run on or restored from a snapshot.
TEST(Fidelity, FastRunsRepeatBitForBit) {
  Simulation first(test::small_pile()), second(test::small_pile());
  first.set_fidelity(Fidelity::kFast);
  second.set_fidelity(Fidelity::kFast);
  const Snapshot start = first.snapshot();
  sweep(first);
  sweep(second);
  EXPECT_EQ(first.snapshot().to_bytes(), second.snapshot().to_bytes());
  second.restore(start);
  sweep(second);
  EXPECT_EQ(first.snapshot().to_bytes(), second.snapshot().to_bytes());
}

}  // namespace
}  // namespace plr::sim
