// The stages of pick_candidates (sim/actions/pick_pipeline.hpp), each on a
// few hand-placed 0.4 m boxes whose answers can be worked out by hand.
#include "pick_pipeline.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "plr/sim/testing/worlds.hpp"

#include "scene.hpp"

namespace plr::actions::pick {
namespace {

using sim::testing::make_box;

sim::World trailer_world(std::vector<sim::Box> boxes) {
  sim::World w;
  w.trailer = {2.5, 2.7, 16.0};
  w.boxes = std::move(boxes);
  return w;
}

sim::Box turned(sim::Box b, double yaw) {
  b.pose.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return b;
}

// The scene of `w` (which must outlive it) for Pick(low, centre), the robot at base_x 8.
PickScene scene_of(const sim::World& w,
                   sim::Action action = sim::make_pick(sim::Height::kLow, sim::Side::kCenter)) {
  const auto obs = sim::testing::small_scene_observation();
  return query_scene(w, sim::analyse(w, obs), action, obs, testing::robot(), Geometry{},
                     plr::sim::home_configuration(8.0));
}

Approach square(const PickScene& s, std::size_t i, bool alternative = false) {
  return approach(s, Geometry{}, i, *s.faces[i], alternative);
}

std::vector<std::size_t> true_at(const std::vector<bool>& v) {
  std::vector<std::size_t> out;
  for (std::size_t i = 0; i < v.size(); ++i)
    if (v[i]) out.push_back(i);
  return out;
}

TEST(PickScene, TheRegionIsTheActionsHeightAndThirdTheNoseStopsAtTheNearestLowBox) {
  // A column of two (a wall: 0.8 m > h_pile) in the middle, one box on the
  // right (a pile box, high for a pile), one up on the left.
  const sim::World w = trailer_world({make_box(1, 10.2, 0, 0), make_box(2, 10.2, 0, 0.4),
                                      make_box(3, 10.1, -0.9, 0), make_box(4, 9.5, 0.9, 0.3)});
  const PickScene s = scene_of(w);
  EXPECT_EQ(true_at(s.in_region), (std::vector<std::size_t>{0, 1}));
  // Boxes whose bottom is under the nose's top (0.25 m + 3 cm): not box 4.
  EXPECT_DOUBLE_EQ(s.nearest, 9.9);
  ASSERT_TRUE(s.faces[0]);
  EXPECT_TRUE(s.faces[0]->n.isApprox(Eigen::Vector3d::UnitX()));
  EXPECT_TRUE(s.faces[0]->centre.isApprox(Eigen::Vector3d(10.0, 0, 0.2)));
  EXPECT_DOUBLE_EQ(s.faces[0]->half_w, 0.2);
  EXPECT_GT(s.plate_depth, 0.0);
}

TEST(PickScene, ABoxTiltedOnAnEdgeHasNoFace) {
  sim::Box b = make_box(1, 10.2, 0, 0.1);
  b.pose.linear() = Eigen::AngleAxisd(M_PI / 4, Eigen::Vector3d::UnitY()).toRotationMatrix();
  const sim::World w = trailer_world({b});
  const PickScene s = scene_of(w);
  ASSERT_TRUE(s.in_front(0));
  EXPECT_FALSE(s.faces[0]);
}

TEST(FacesToTry, ASquareBoxHasOneFaceATurnedOneItsOtherSideToo) {
  const sim::World w =
      trailer_world({make_box(1, 10.2, 0, 0), turned(make_box(2, 10.2, 0.8, 0), 0.6)});
  const PickScene s = scene_of(w);
  ASSERT_TRUE(s.faces[0] && s.faces[1]);
  EXPECT_EQ(faces_to_try(s, 0).size(), 1u);
  const auto faces = faces_to_try(s, 1);
  ASSERT_EQ(faces.size(), 2u);
  EXPECT_TRUE(faces[0].n.isApprox(Eigen::Vector3d(std::cos(0.6), std::sin(0.6), 0)));
  EXPECT_TRUE(faces[1].n.isApprox(Eigen::Vector3d(std::sin(0.6), -std::cos(0.6), 0)));
}

TEST(StackedOn, AreTheBoxesOfTheColumnAboveNotThoseBeside) {
  const sim::World w = trailer_world({make_box(1, 10.2, 0, 0), make_box(2, 10.2, 0, 0.4),
                                      make_box(3, 10.2, 0, 0.8), make_box(4, 10.2, 0.41, 0)});
  const PickScene s = scene_of(w);
  EXPECT_EQ(true_at(stacked_on(s, 0)), (std::vector<std::size_t>{1, 2}));
  EXPECT_EQ(true_at(stacked_on(s, 1)), (std::vector<std::size_t>{2}));
  EXPECT_TRUE(true_at(stacked_on(s, 3)).empty());
}

TEST(PlateOffsets, SlidesOnTheFaceThenItsEdgesThenHalfACupPitch) {
  // A 0.4 m face: slides of 0, ±5 and ±10 cm each way (the centre stays
  // 10 cm inside), then the 8 edges and corners.
  Face f;
  f.half_w = f.half_up = 0.2;
  const auto offsets = plate_offsets(Geometry{}, f, 0.2, false);
  ASSERT_EQ(offsets.size(), 25u + 8u);
  EXPECT_EQ(offsets.front(), std::make_pair(0.0, 0.0));
  EXPECT_EQ(offsets[25], std::make_pair(0.2, 0.0));
  EXPECT_EQ(offsets.back(), std::make_pair(-0.2, -0.2));
  // After a failed grip: half of the 0.1 m pitch off centre, 9 more.
  const auto fewer = plate_offsets(Geometry{}, f, 0.2, true);
  ASSERT_EQ(fewer.size(), 33u + 9u);
  EXPECT_EQ(fewer.back(), std::make_pair(-0.05, -0.05));
}

TEST(PlateAt, KeepsThePlateOffTheFloorAndInsideTheTrailer) {
  const sim::World w = trailer_world({make_box(1, 10.2, 1.0, 0)});
  const PickScene s = scene_of(w, sim::make_pick(sim::Height::kLow, sim::Side::kLeft));
  const Approach a = square(s, 0);
  const Geometry g;
  // 1.25 m half width less the plate's half (0.25 m) and 3 cm.
  EXPECT_DOUBLE_EQ(a.ylim, 1.25 - 0.25 - 0.03);
  const Eigen::Vector3d p = plate_at(w, g, a, 0.1, -0.1);
  EXPECT_DOUBLE_EQ(p.y(), a.ylim);
  EXPECT_DOUBLE_EQ(p.z(), g.plate_half_height() + kFloorGap);
  EXPECT_DOUBLE_EQ(p.x(), 10.0);
}

TEST(Corridor, ANeighbourStandingOutStopsThePlateShortBeyondTheCupsReachItRefuses) {
  // Box 2 on box 1, which stands out 1 cm: the plate on box 2's face
  // overlaps box 1 and stops grasp_gap short of it.
  const Geometry g;
  sim::World w =
      trailer_world({make_box(1, 10.19, 0, 0), make_box(2, 10.2, 0, 0.4, {0.4, 0.4, 0.3})});
  {
    const PickScene s = scene_of(w);
    const Approach a = square(s, 1);
    const Corridor c = corridor(s, g, a, a.point);
    EXPECT_NEAR(c.back, g.grasp_gap + 0.01, 1e-12);
    EXPECT_EQ(c.proud, 0u);
    EXPECT_FALSE(corridor_refusal(s, g, c));
  }
  w.boxes[0] = make_box(1, 10.17, 0, 0);  // 3 cm: beyond kProud
  const PickScene s = scene_of(w);
  const Approach a = square(s, 1);
  const auto why = corridor_refusal(s, g, corridor(s, g, a, a.point));
  ASSERT_TRUE(why);
  EXPECT_EQ(why->kind, Refusal::Kind::kProud);
  EXPECT_EQ(why->box, 1u);
}

TEST(Corridor, ABoxInFrontLeavesLessRoomTooLittleItRefuses) {
  const Geometry g;
  // Box 2's back 40 cm before box 1's face: room for the whole stand-off,
  // unless the plate's body takes more.
  sim::World w = trailer_world({make_box(1, 10.2, 0, 0), make_box(2, 9.4, 0, 0)});
  {
    const PickScene s = scene_of(w);
    const Approach a = square(s, 0);
    const Corridor c = corridor(s, g, a, plate_at(w, g, a, 0, 0));
    EXPECT_NEAR(c.room, std::min(g.pregrasp_distance, 0.4 - kClearance - s.plate_depth), 1e-12);
    EXPECT_FALSE(corridor_refusal(s, g, c));
  }
  w.boxes[1] = make_box(2, 9.75, 0, 0);  // 5 cm before the face
  const PickScene s = scene_of(w);
  const Approach a = square(s, 0);
  const auto why = corridor_refusal(s, g, corridor(s, g, a, plate_at(w, g, a, 0, 0)));
  ASSERT_TRUE(why);
  EXPECT_EQ(why->kind, Refusal::Kind::kNoRoom);
  EXPECT_EQ(why->box, 2u);
}

TEST(SealedGroup, ThePlateOnTheSeamOfAColumnTakesBothBoxesAnAlternativeFaceOne) {
  // The plate centred on the seam at 0.4 m: of its 4 rows of cups (0.1 m
  // apart) two lie on each box, of its 5 columns the 3 inside the rims.
  const Geometry g;
  const sim::World w = trailer_world({make_box(1, 10.2, 0, 0), make_box(2, 10.2, 0, 0.4)});
  const PickScene s = scene_of(w);
  const std::vector<bool> stacked = stacked_on(s, 0);
  const Approach a = square(s, 0);
  const Eigen::Vector3d p = plate_at(w, g, a, 0, 0.4 - a.point.z());
  ASSERT_NEAR(p.z(), 0.4, 1e-12);
  const int own = cups_on(s, g, a, 0, p);
  EXPECT_EQ(own, 6);
  const Eigen::Vector3d surface = p - g.grasp_gap * a.face.n;
  const Sealed both = sealed_group(s, g, a, stacked, p, surface, own);
  EXPECT_EQ(both.group, (std::vector<std::size_t>{0, 1}));
  EXPECT_EQ(both.cups, (std::vector<int>{6, 6}));
  const Sealed alone = sealed_group(s, g, square(s, 0, true), stacked, p, surface, own);
  EXPECT_EQ(alone.group, (std::vector<std::size_t>{0}));
}

TEST(LiftHeight, OverTheNoseOffTheFloorClearOfATiltedSupport) {
  const Geometry g;
  // On the floor: over the lowered nose (0.25 m) and 3 cm.
  const sim::World floor = trailer_world({make_box(1, 10.2, 0, 0)});
  EXPECT_DOUBLE_EQ(lift_height(scene_of(floor), g, {0}), g.nose_top + kMargin);
  // On a flat box: the retract lift.
  const sim::World stack = trailer_world({make_box(1, 10.2, 0, 0), make_box(2, 10.2, 0, 0.4)});
  EXPECT_DOUBLE_EQ(lift_height(scene_of(stack), g, {1}), g.retract_lift);
  // Sunk 6.5 cm into a tilted top: clear of it, by kClearance and the slack.
  const sim::World sunk =
      trailer_world({make_box(1, 10.2, 0, 0, {0.4, 0.4, 0.465}), make_box(2, 10.2, 0, 0.4)});
  EXPECT_NEAR(lift_height(scene_of(sunk), g, {1}), 0.065 + kClearance + kLiftSlack, 1e-12);
}

TEST(CeilingRoom, WhatTheGroupAndThePlateCanRiseUnderTheCeiling) {
  const Geometry g;
  // A carton of a ceiling-high wall, 5 cm under a 2.7 m ceiling: it rises
  // 3 cm, not the 5 cm of the retract lift.
  const sim::World top = trailer_world({make_box(1, 10.2, 0, 2.12, {0.5, 0.5, 0.53})});
  const PickScene s = scene_of(top);
  EXPECT_NEAR(ceiling_room(s, g, {0}, {10.0, 0.0, 2.385}), 0.03, 1e-12);
  // A plate higher than the box: its top sets the room.
  EXPECT_NEAR(ceiling_room(s, g, {0}, {10.0, 0.0, 2.47}), 0.01, 1e-12);
  // Against the ceiling: none.
  EXPECT_EQ(ceiling_room(s, g, {0}, {10.0, 0.0, 2.6}), 0.0);
  // Lower down, far more than any lift.
  const sim::World low = trailer_world({make_box(1, 10.2, 0, 0)});
  EXPECT_GT(ceiling_room(scene_of(low), g, {0}, {10.0, 0.0, 0.2}), 2.0);
}

TEST(RidersOn, OneWallBoxOnTheGroupRidesTwoDoNot) {
  // Columns of three: the top box rests on the two taken under it.
  const sim::World one = trailer_world(
      {make_box(1, 10.2, 0, 0), make_box(2, 10.2, 0, 0.4), make_box(3, 10.2, 0, 0.8)});
  EXPECT_EQ(riders_on(scene_of(one), {0, 1}, 0.05), (std::vector<std::size_t>{2}));
  // Two columns, both bottoms taken: two boxes would ride, more than kMaxRiders.
  const sim::World two = trailer_world(
      {make_box(1, 10.2, -0.21, 0), make_box(2, 10.2, -0.21, 0.4), make_box(3, 10.2, 0.21, 0),
       make_box(4, 10.2, 0.21, 0.4), make_box(5, 10.2, -0.21, 0.8), make_box(6, 10.2, 0.21, 0.8)});
  EXPECT_TRUE(riders_on(scene_of(two), {0, 2}, 0.05).empty());
}

TEST(WayOut, WhatRestsOnTheBoxOrStandsHighInFrontOfItRefuses) {
  const Eigen::Vector3d n = Eigen::Vector3d::UnitX();
  const sim::World stack = trailer_world({make_box(1, 10.2, 0, 0), make_box(2, 10.2, 0, 0.4)});
  const auto rests = way_out_refusal(scene_of(stack), {0}, 0.28, 0.43, n);
  ASSERT_TRUE(rests);
  EXPECT_EQ(rests->kind, Refusal::Kind::kRestsOn);
  EXPECT_EQ(std::make_pair(rests->box, rests->of), std::make_pair(2u, 1u));
  EXPECT_FALSE(way_out_refusal(scene_of(stack), {0, 1}, 0.28, 0.43, n));
  // In front, lower than the lifted box's bottom (and kClearance): it passes over.
  sim::World front =
      trailer_world({make_box(1, 10.2, 0, 0), make_box(2, 9.7, 0, 0, {0.4, 0.4, 0.2})});
  EXPECT_FALSE(way_out_refusal(scene_of(front), {0}, 0.28, 0.43, n));
  front.boxes[1] = make_box(2, 9.7, 0, 0, {0.4, 0.4, 0.5});
  const auto blocked = way_out_refusal(scene_of(front), {0}, 0.28, 0.43, n);
  ASSERT_TRUE(blocked);
  EXPECT_EQ(blocked->kind, Refusal::Kind::kInTheWay);
  EXPECT_EQ(std::make_pair(blocked->box, blocked->of), std::make_pair(2u, 1u));
}

TEST(InTheWay, ABoxTiltedOnAnEdgeCountsOnlyWhenAsked) {
  sim::Box leaning = make_box(2, 10.2, 0, 0.45);
  leaning.pose.linear() = Eigen::AngleAxisd(M_PI / 4, Eigen::Vector3d::UnitX()).toRotationMatrix();
  const sim::World w = trailer_world({make_box(1, 10.2, 0, 0), leaning});
  const PickScene s = scene_of(w);
  EXPECT_FALSE(in_the_way(s, {0}, s.outline[0], 0.4, 0.7, false));
  EXPECT_EQ(in_the_way(s, {0}, s.outline[0], 0.4, 0.7, true), 1u);
}

TEST(ReachRefusal, APoseTheArmCannotReachFromTheBaseRefuses) {
  const sim::World w = trailer_world({make_box(1, 10.2, 0, 0)});
  const auto obs = sim::testing::small_scene_observation();
  // A lone 0.4 m box is a pile, high for a pile.
  const auto c = pick_candidates(
      w, sim::analyse(w, obs), sim::make_pick(sim::Height::kHigh, sim::Side::kCenter), obs,
      testing::robot(), Geometry{}, plr::sim::home_configuration(8.0), 1);
  ASSERT_EQ(c.size(), 1u);
  EXPECT_FALSE(reach_refusal(testing::robot(), c[0], plr::sim::home_configuration(8.0)));
  PickCandidate far = c[0];
  far.base_x = 2.0;
  const auto why = reach_refusal(testing::robot(), far, plr::sim::home_configuration(8.0));
  ASSERT_TRUE(why);
  EXPECT_EQ(why->kind, Refusal::Kind::kUnreachable);
  EXPECT_EQ(to_string(*why), "no arm pose reaches its face from base x 2.00 m");
}

Grip grip(std::vector<std::size_t> group, std::vector<int> cups,
          std::vector<std::size_t> riders = {}) {
  Grip g;
  g.group = std::move(group);
  g.cups = std::move(cups);
  g.riders = std::move(riders);
  return g;
}

TEST(GripRank, MoreBoxesFirstAfterAFailedGripMoreCupsOnTheBoxNothingRidingBeforeAll) {
  const Grip two = grip({0, 1}, {6, 6}), one = grip({0}, {20}), fewer_cups = grip({0, 1}, {6, 3});
  EXPECT_GT(grip_rank(two, false), grip_rank(one, false));
  EXPECT_GT(grip_rank(two, false), grip_rank(fewer_cups, false));
  EXPECT_GT(grip_rank(one, true), grip_rank(two, true));
  EXPECT_GT(grip_rank(one, false), grip_rank(grip({0, 1}, {6, 6}, {2}), false));
  EXPECT_EQ(grip_rank(two, false), std::make_tuple(true, 2, 6, 12));
}

Ranked entry(std::vector<std::uint32_t> boxes, double x_bin, double top, double centre,
             bool rider = false) {
  PickCandidate c;
  c.box = boxes.front();
  c.boxes = std::move(boxes);
  if (rider) c.riders = {99};
  return {c, x_bin, top, centre};
}

std::vector<std::uint32_t> firsts(const std::vector<PickCandidate>& c) {
  std::vector<std::uint32_t> out;
  for (const auto& k : c) out.push_back(k.box);
  return out;
}

TEST(Rank, NearFirstThenHighThenCentredRidersLastEachGroupOnce) {
  std::vector<Ranked> r;
  r.push_back(entry({1}, 1, 0.4, 0.0));
  r.push_back(entry({2}, 0, 0.4, 0.5, true));  // a rider: after every other
  r.push_back(entry({3}, 0, 0.4, 0.3));
  r.push_back(entry({4}, 0, 0.8, 0.6));     // higher up
  r.push_back(entry({5}, 0, 0.4005, 0.1));  // as high, within 1 mm: nearer the axis first
  r.push_back(entry({6, 4}, 0, 0.8, 0.7));  // 4 with 6
  r.push_back(entry({4, 6}, 0, 0.8, 0.8));  // the same group found from 4
  EXPECT_EQ(firsts(rank(r, 100)), (std::vector<std::uint32_t>{4, 6, 5, 3, 1, 2}));
  EXPECT_EQ(firsts(rank(r, 2)), (std::vector<std::uint32_t>{4, 6}));
}

TEST(Refusal, SaysWhatIsInTheWay) {
  EXPECT_EQ(to_string({Refusal::Kind::kProud, 3}), "box 3 stands out before its face");
  EXPECT_EQ(to_string({Refusal::Kind::kNoRoom, 3}), "box 3 leaves the plate no room before it");
  EXPECT_EQ(to_string({Refusal::Kind::kRestsOn, 3, 4}), "box 3 rests on box 4");
  EXPECT_EQ(to_string({Refusal::Kind::kInTheWay, 3, 4}), "box 3 is in the way out of box 4");
  EXPECT_EQ(to_string({Refusal::Kind::kNoCup}), "no whole cup on its face");
  EXPECT_EQ(to_string({Refusal::Kind::kNoFace}), "no face the plate seals on");
}

TEST(BestGrip, TakesTheColumnTogetherElseSaysWhyTheFirstPoseWasRefused) {
  // Box 2 rests on box 1 off its centre: it cannot ride on box 1 alone.
  const Geometry g;
  const sim::World w = trailer_world({make_box(1, 10.2, 0, 0), make_box(2, 10.2, 0.25, 0.4)});
  const PickScene s = scene_of(w);
  const std::vector<bool> stacked = stacked_on(s, 0);
  const auto both = best_grip(s, g, square(s, 0), stacked, false, nullptr);
  ASSERT_TRUE(both);
  EXPECT_EQ(both->group, (std::vector<std::size_t>{0, 1}));
  EXPECT_TRUE(both->riders.empty());
  // Through an alternative face the box is taken alone.
  std::optional<Refusal> why;
  EXPECT_FALSE(best_grip(s, g, square(s, 0, true), stacked, false, &why));
  ASSERT_TRUE(why);
  EXPECT_EQ(to_string(*why), "box 2 rests on box 1");
}

TEST(MakeCandidate, ThePlateAtTheFaceBackedOffForThePreGraspTheBaseShortOfTheNose) {
  const Geometry g;
  const sim::World w = trailer_world({make_box(1, 10.2, 0, 0)});
  const PickScene s = scene_of(w);
  const Approach a = square(s, 0);
  const auto gr = best_grip(s, g, a, stacked_on(s, 0), false, nullptr);
  ASSERT_TRUE(gr);
  const PickCandidate c = make_candidate(s, g, a, *gr);
  EXPECT_EQ(c.boxes, std::vector<std::uint32_t>{1});
  EXPECT_NEAR(c.grasp.position.x(), 10.0 - g.grasp_gap, 1e-12);
  EXPECT_NEAR(c.pregrasp.position.x(), 10.0 - g.pregrasp_distance, 1e-12);
  EXPECT_NEAR(c.lift.position.z() - c.grasp.position.z(), g.nose_top + kMargin, 1e-12);
  // The low plate stays ahead of the lowered nose's tip.
  EXPECT_NEAR(c.base_x, 10.0 - g.pregrasp_distance - g.conveyor_length - g.nose_clearance, 1e-12);
  EXPECT_EQ(std::count(c.cups_open.begin(), c.cups_open.end(), true), c.cups);
}

}  // namespace
}  // namespace plr::actions::pick
