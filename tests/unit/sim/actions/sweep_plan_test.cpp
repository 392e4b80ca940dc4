// The three sweeps on hand-made scenes: each acts on what its kind is for,
// is not applicable without it, and they differ where they go.
#include <gtest/gtest.h>

#include "plr/actions/instantiate.hpp"
#include "plr/sim/testing/worlds.hpp"

namespace plr::actions {
namespace {

using sim::Height;
using sim::testing::add_wall;
using sim::testing::make_box;

sim::World trailer() {
  sim::World w;
  w.trailer = {2.5, 2.7, 16.0};
  return w;
}

std::optional<SweepPlan> plan(const sim::World& w, Height h, const Geometry& g = {}) {
  sim::ObservationParams obs;
  obs.h_pile = 1.35;
  return sweep_plan(w, sim::analyse(w, obs), sim::make_sweep(h), g, 0.3);
}

// A floor layer two boxes deep and three wide, front face at x = 10.
sim::World floor_pile() {
  sim::World w = trailer();
  std::uint32_t id = 1;
  for (int row = 0; row < 2; ++row)
    for (int col = -1; col <= 1; ++col)
      w.boxes.push_back(make_box(id++, 10.2 + 0.4 * row, 0.45 * col, 0));
  return w;
}

TEST(SweepPlan, NothingInFrontNothingToSweep) {
  for (Height h : {Height::kLow, Height::kMid, Height::kHigh})
    EXPECT_FALSE(plan(trailer(), h)) << sim::to_string(h);
}

TEST(SweepPlan, LowSweepsTheFloorLayerAndMidGoesDeeper) {
  const sim::World w = floor_pile();
  const auto low = plan(w, Height::kLow);
  const auto mid = plan(w, Height::kMid);
  ASSERT_TRUE(low);
  ASSERT_TRUE(mid);
  const Geometry g;
  const double tip = g.conveyor_length + 0.3 + g.scoop_lip;
  // Low: the scoop tip just past the floor layer's far end (10.8 m).
  EXPECT_NEAR(low->end_base_x + tip, 10.8 + g.sweep_overshoot, 1e-9);
  EXPECT_NEAR(mid->end_base_x + tip, 10.8 + g.sweep_dig, 1e-9);
  EXPECT_EQ(low->lift, 0.0);
  EXPECT_EQ(mid->lift, 0.0);
  EXPECT_FALSE(low->lower_at_end);
  // Both start just behind the pile, the nose tip clear of it: what rides
  // out on the scoop comes back that far, not across the trailer.
  EXPECT_NEAR(low->start_base_x + tip, 10.0 - g.nose_clearance, 1e-9);
  EXPECT_NEAR(mid->start_base_x + tip, 10.0 - g.nose_clearance, 1e-9);
  EXPECT_EQ(low->swept.size(), 6u);
  // Nothing stands high enough for the raised nose.
  EXPECT_FALSE(plan(w, Height::kHigh));
}

TEST(SweepPlan, AWallAloneIsNotLowSweptButDugIntoAndPulledDown) {
  sim::World w = trailer();
  add_wall(w, 12.0, 5, 5);  // 2 m high
  EXPECT_FALSE(plan(w, Height::kLow));
  const auto mid = plan(w, Height::kMid);
  const auto high = plan(w, Height::kHigh);
  ASSERT_TRUE(mid);
  ASSERT_TRUE(high);
  const Geometry g;
  const double tip = g.conveyor_length + 0.3 + g.scoop_lip;
  EXPECT_NEAR(mid->end_base_x + tip, 12.0 + g.sweep_dig, 1e-9);
  // The raised nose meets the wall about halfway up, then lowers.
  EXPECT_GT(high->lift, 0.5);
  EXPECT_LE(high->lift, g.nose_lift_max);
  EXPECT_TRUE(high->lower_at_end);
  EXPECT_NEAR(high->end_base_x + tip, 12.0 + g.sweep_high_in, 1e-9);
  EXPECT_EQ(high->swept.size(), 25u);
}

// A wall whose top box overhangs it by 0.4 m towards the robot (as the top
// of a column leaning out, A2 s7): the raised scoop meets the wall about
// halfway up, so it is driven in past the face it meets there, not past the
// overhang's (where it would stop 0.2 m short of the wall and move nothing).
TEST(SweepPlan, TheHighSweepDigsInPastTheFaceAtTheScoopsHeightUnderAnOverhang) {
  sim::World w = trailer();
  add_wall(w, 12.0, 3, 3);                                           // 1.2 m high
  w.boxes.push_back(make_box(10, 12.1, 0.0, 1.2, {1.0, 0.4, 0.4}));  // x 11.6 to 12.6
  const auto high = plan(w, Height::kHigh);
  ASSERT_TRUE(high);
  const Geometry g;
  const double tip = g.conveyor_length + 0.3 + g.scoop_lip;
  ASSERT_GT(high->lift + g.nose_top, 0.4);  // the scoop is at the wall's second row
  ASSERT_LT(high->lift + g.nose_top, 1.2);
  EXPECT_NEAR(high->end_base_x + tip, 12.0 + g.sweep_high_in, 1e-9);
  EXPECT_NEAR(high->start_base_x + tip, 11.6 - g.nose_clearance, 1e-9);
}

TEST(SweepPlan, TheLowSweepStopsAtTheWallBehindThePile) {
  sim::World w = floor_pile();
  add_wall(w, 11.0, 5, 5);
  const auto low = plan(w, Height::kLow);
  const auto mid = plan(w, Height::kMid);
  ASSERT_TRUE(low);
  ASSERT_TRUE(mid);
  const Geometry g;
  const double tip = g.conveyor_length + 0.3 + g.scoop_lip;
  EXPECT_LT(low->end_base_x + tip, 11.0);
  EXPECT_NEAR(mid->end_base_x + tip, 11.0 + g.sweep_dig, 1e-9);
}

// A floor layer beside the wall's foot, further in than the wall's face (A2
// seed 12: no sweep could lower its scoop, "goal: nose_scoop - box 80"):
// the nose, as wide as the trailer, comes down short of the wall too.
TEST(SweepPlan, TheNoseComesDownShortOfTheWallBesideAFloorLayerBeyondIt) {
  sim::World w = trailer();
  std::uint32_t id = 1;
  for (int col = -2; col <= 0; ++col)
    for (int row = 0; row < 4; ++row)
      w.boxes.push_back(make_box(id++, 10.2, 0.41 * col, 0.4 * row));
  for (double x : {10.6, 11.0}) w.boxes.push_back(make_box(id++, x, 0.82, 0));
  const sim::SceneAnalysis scene = sim::analyse(w, [] {
    sim::ObservationParams obs;
    obs.h_pile = 1.35;
    return obs;
  }());
  ASSERT_FALSE(scene.first_wall.empty());
  ASSERT_FALSE(scene.front_pile.empty());
  ASSERT_GT(scene.pile_near_x, scene.wall_near_x + 0.2);  // the world is what this is about
  const Geometry g;
  const double tip = g.conveyor_length + 0.3 + g.scoop_lip;
  for (Height h : {Height::kLow, Height::kMid}) {
    const auto p = plan(w, h);
    ASSERT_TRUE(p) << sim::to_string(h);
    EXPECT_LE(p->start_base_x + tip, 10.0 - g.nose_clearance + 1e-9) << sim::to_string(h);
  }
}

TEST(SweepPlan, ABoxStrayedTowardsTheDoorIsLowSweptOnItsOwn) {
  // A box 4 m short of the floor layer: the low sweep takes it alone,
  // instead of pushing it on into the layer beyond; it stops just short of
  // the layer.
  sim::World w = floor_pile();
  w.boxes.push_back(make_box(7, 6.2, 0.8, 0));
  const auto low = plan(w, Height::kLow);
  ASSERT_TRUE(low);
  const Geometry g;
  const double tip = g.conveyor_length + 0.3 + g.scoop_lip;
  EXPECT_NEAR(low->start_base_x + tip, 6.0 - g.nose_clearance, 1e-9);
  EXPECT_NEAR(low->end_base_x + tip, 10.0 - g.nose_clearance, 1e-9);
}

TEST(SweepPlan, NeverPastTheTrailersFrontWall) {
  sim::World w = trailer();
  add_wall(w, 15.7, 5, 5);
  const auto mid = plan(w, Height::kMid);
  ASSERT_TRUE(mid);
  const Geometry g;
  EXPECT_LE(mid->end_base_x + g.conveyor_length + 0.3 + g.scoop_lip, 16.0);
}

}  // namespace
}  // namespace plr::actions
