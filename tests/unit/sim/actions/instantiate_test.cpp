// Pick points, drop-off places and straight-line checks of the strategy
// executor (plugins/strategy_executor/src/instantiate.cpp), on built and
// generated worlds with the shipped robot.
#include "plr/actions/instantiate.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "plr/sim/generators.hpp"
#include "plr/sim/testing/worlds.hpp"

namespace plr::actions {
namespace {

const sim::RobotModel& robot() {
  static const sim::RobotModel m = sim::load_robot().value();
  return m;
}

sim::JointVector home(double base_x) {
  sim::JointVector q;
  q << base_x, 0.0, -1.0, 2.0, 0.0, 0.5, 0.0, 0.0;
  return q;
}

std::vector<PickCandidate> candidates(const sim::World& w, double base_x = 8.0) {
  return pick_candidates(w, sim::analyse(w), sim::make_pick(sim::Height::kHigh, sim::Side::kCenter),
                         {}, robot(), {}, home(base_x), 1000);
}

const PickCandidate* find(const std::vector<PickCandidate>& c, std::uint32_t box) {
  const auto it = std::find_if(c.begin(), c.end(), [&](const auto& k) { return k.box == box; });
  return it == c.end() ? nullptr : &*it;
}

sim::World trailer_world() {
  sim::World w;
  w.trailer = {2.5, 2.7, 16.0};
  return w;
}

TEST(PickCandidates, EveryTopBoxOfTheFrontRowOfAnA1WallIsAPickPoint) {
  // The wrist turns the plate square to any face: the side columns and the
  // top row, up to under the ceiling, are reached from behind the lowered nose.
  const sim::World w = sim::without_masses(sim::generate_world(sim::EnvFamily::kA1, 1));
  const auto c = candidates(w);
  double front = 1e9;
  for (const auto& b : w.boxes) front = std::min(front, sim::bounds(b).x0);
  int tops = 0;
  for (const auto& b : w.boxes) {
    const auto bb = sim::bounds(b);
    if (bb.x0 > front + 0.05) continue;
    const bool covered = std::any_of(w.boxes.begin(), w.boxes.end(), [&](const sim::Box& o) {
      const auto ob = sim::bounds(o);
      return o.id != b.id && ob.z0 > bb.z1 - 0.01 && ob.x0 < bb.x1 && ob.x1 > bb.x0 &&
             ob.y0 < bb.y1 - 0.01 && ob.y1 > bb.y0 + 0.01;
    });
    if (covered) continue;
    ++tops;
    const PickCandidate* k = find(c, b.id);
    ASSERT_NE(k, nullptr) << "top box " << b.id << " at y " << b.pose.translation().y() << " z "
                          << bb.z1;
    EXPECT_NEAR(k->grasp.yaw, 0.0, 1e-9);
    EXPECT_LE(std::abs(k->grasp.position.y()), w.trailer.width / 2 - 0.25);
  }
  EXPECT_GE(tops, 4);
}

TEST(PickCandidates, PlateStopsShortOfAProudNeighbourWithinTheCupsReach) {
  // A 0.3 m box on one standing out 1 cm: the 0.4 m plate overlaps the lower
  // box, so it stops 5 mm short of that one, 1.5 cm from its target.
  sim::World w = trailer_world();
  w.boxes.push_back(sim::testing::make_box(1, 10.19, 0.0, 0.0, {0.4, 0.4, 0.4}));
  w.boxes.push_back(sim::testing::make_box(2, 10.2, 0.0, 0.4, {0.4, 0.4, 0.3}));
  const auto c = candidates(w);
  const PickCandidate* k = find(c, 2);
  ASSERT_NE(k, nullptr);
  EXPECT_NEAR(k->grasp.position.x(), 9.99 - 0.005, 1e-9);
  // A neighbour standing out 3 cm leaves the face beyond the cups' reach.
  w.boxes[0] = sim::testing::make_box(1, 10.17, 0.0, 0.0, {0.4, 0.4, 0.4});
  EXPECT_EQ(find(candidates(w), 2), nullptr);
}

TEST(PickCandidates, ABoxThatCannotComeOutOverTheOneInFrontIsNotAPickPoint) {
  // A wide box behind a lower one that stands beside the plate's path but
  // under the box's own width: lifted 5 cm it would still hit it.
  sim::World w = trailer_world();
  w.boxes.push_back(sim::testing::make_box(1, 10.2, 0.0, 0.0, {0.4, 0.7, 0.6}));
  // Beside the plate's path (|y| > 0.27), under the box's width (|y| < 0.35).
  w.boxes.push_back(sim::testing::make_box(2, 9.8, -0.425, 0.0, {0.4, 0.25, 0.5}));
  EXPECT_EQ(find(candidates(w), 1), nullptr);
  // Lower than the lifted box (lifted over the nose, to 0.28 m): it comes out.
  w.boxes[1] = sim::testing::make_box(2, 9.8, -0.425, 0.0, {0.4, 0.25, 0.2});
  EXPECT_NE(find(candidates(w), 1), nullptr);
}

TEST(PickCandidates, ABoxRestingOnTheTargetKeepsItInPlace) {
  sim::World w = trailer_world();
  w.boxes.push_back(sim::testing::make_box(1, 10.2, 0.0, 0.0));
  w.boxes.push_back(sim::testing::make_box(2, 10.6, 0.0, 0.4));  // behind and above: not on it
  w.boxes.push_back(sim::testing::make_box(3, 10.2, 0.0, 0.4));  // on it
  const auto c = candidates(w);
  EXPECT_EQ(find(c, 1), nullptr);
  EXPECT_NE(find(c, 3), nullptr);
}

TEST(PickCandidates, ATurnedBoxIsFacedSquarely) {
  sim::World w = trailer_world();
  sim::Box b = sim::testing::make_box(1, 10.2, 0.3, 0.0);
  b.pose.linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  w.boxes.push_back(b);
  const std::vector<PickCandidate> c = candidates(w);
  const PickCandidate* k = find(c, 1);
  ASSERT_NE(k, nullptr);
  EXPECT_NEAR(k->grasp.yaw, 0.3, 1e-9);
  // Pre-grasp, grasp and retract lie on the face's normal.
  const Eigen::Vector3d n(std::cos(0.3), std::sin(0.3), 0.0);
  const Eigen::Vector3d d = k->grasp.position - k->pregrasp.position;
  EXPECT_LT((d - d.dot(n) * n).norm(), 1e-9);
}

TEST(CoveredCups, CountsTheCupsWhoseRimLiesOnTheFace) {
  const Geometry g;
  EXPECT_EQ(covered_cups(g, 0.25, 0.25, 0, 0), 12);  // a 0.5 m face takes the whole grid
  // A 0.29 m face: the centred grid straddles it with one column of three,
  // half a cup pitch off centre puts two columns on it.
  EXPECT_EQ(covered_cups(g, 0.145, 0.145, 0, 0), 2);
  EXPECT_EQ(covered_cups(g, 0.145, 0.145, 0.25 / 3, 0), 4);
  EXPECT_EQ(covered_cups(g, 0.145, 0.145, 0.5, 0), 0);
}

TEST(PickCandidates, AfterAFailedGripThePlateCoversMoreCups) {
  // A 0.29 m box on the floor: the plate, kept off the floor, covers its two
  // lower rows; centred across, one column.
  sim::World w = trailer_world();
  w.boxes.push_back(sim::testing::make_box(1, 6.2, 0.0, 0.0, {0.4, 0.29, 0.29}));
  const auto centred = candidates(w);
  ASSERT_EQ(centred.size(), 1u);
  EXPECT_EQ(centred[0].cups, 2);
  EXPECT_NEAR(centred[0].grasp.position.y(), 0.0, 1e-9);
  const auto moved =
      pick_candidates(w, sim::analyse(w), sim::make_pick(sim::Height::kHigh, sim::Side::kCenter),
                      {}, robot(), {}, home(8.0), 1000, {1});
  ASSERT_EQ(moved.size(), 1u);
  EXPECT_EQ(moved[0].cups, 4);
  EXPECT_NEAR(std::abs(moved[0].grasp.position.y()), 0.25 / 3, 1e-9);
}

TEST(DropOff, PlacesHoldTheBoxOverTheConveyorAndTurnTheWristSideways) {
  sim::World w = trailer_world();
  w.boxes.push_back(sim::testing::make_box(7, 6.0, 0.0, 1.0, {0.45, 0.55, 0.35}));
  const Geometry g;
  const sim::JointVector at = home(5.0);
  const auto places = dropoff_targets(w, {7}, robot(), g, at, 6);
  ASSERT_FALSE(places.empty());
  EXPECT_NEAR(std::abs(places.front().yaw), M_PI / 2, 1e-9);
  for (const auto& t : places) {
    const Eigen::Vector3d n(std::cos(t.yaw), std::sin(t.yaw), 0.0);
    const double depth = 0.45;  // along the plate's normal, as gripped
    const Eigen::Vector3d centre = t.position + depth / 2 * n;
    const double along = std::abs(t.yaw) > 1 ? 0.55 : 0.45;
    EXPECT_GE(centre.x() - along / 2, at[sim::kBaseX] - 1e-9);
    EXPECT_LE(centre.x() + along / 2, at[sim::kBaseX] + g.conveyor_length + 1e-9);
    EXPECT_NEAR(centre.y(), 0.0, 1e-9);
    EXPECT_FALSE(robot().arm_ik(t, at).empty());
  }
}

TEST(FollowsLines, SeesALineLeaveTheArmsReach) {
  const sim::JointVector q = home(5.0);
  const sim::PlateTarget here = robot().plate_target(q);
  const Eigen::Vector3d ahead = here.position + Eigen::Vector3d(0.3, 0.0, 0.0);
  EXPECT_TRUE(follows_lines(robot(), q, {{ahead, 0.0}, {here.position, 0.0}}));
  EXPECT_FALSE(follows_lines(robot(), q, {{here.position + Eigen::Vector3d(3.0, 0, 0), 0.0}}));
}

}  // namespace
}  // namespace plr::actions
