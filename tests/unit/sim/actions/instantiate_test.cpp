// Pick points, drop-off places and straight-line checks of the strategy
// executor (plugins/strategy_executor/src/instantiate.cpp), on built and
// generated worlds with the shipped robot.
#include "plr/actions/instantiate.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <unordered_set>

#include "plr/sim/generators.hpp"
#include "plr/sim/testing/worlds.hpp"

namespace plr::actions {
namespace {

const sim::RobotModel& robot() {
  static const sim::RobotModel m = sim::load_robot().value();
  return m;
}

constexpr std::array<sim::Height, 3> kHeights{sim::Height::kLow, sim::Height::kMid,
                                              sim::Height::kHigh};
constexpr std::array<sim::Side, 3> kSides{sim::Side::kLeft, sim::Side::kCenter, sim::Side::kRight};

std::vector<PickCandidate> candidates(const sim::World& w, sim::Action action, double base_x = 8.0,
                                      const Geometry& g = {},
                                      const std::unordered_set<std::uint32_t>& most_cups = {}) {
  const auto obs = sim::testing::small_scene_observation();
  return pick_candidates(w, sim::analyse(w, obs), action, obs, robot(), g,
                         plr::sim::home_configuration(base_x), 1000, most_cups);
}

// The candidates of all nine Pick actions.
std::vector<PickCandidate> candidates(const sim::World& w, double base_x = 8.0) {
  std::vector<PickCandidate> out;
  for (auto h : kHeights)
    for (auto s : kSides)
      for (auto& c : candidates(w, sim::make_pick(h, s), base_x)) out.push_back(std::move(c));
  return out;
}

// The candidate that takes `box` (with others or alone).
const PickCandidate* find(const std::vector<PickCandidate>& c, std::uint32_t box) {
  const auto it = std::find_if(c.begin(), c.end(), [&](const auto& k) {
    return std::find(k.boxes.begin(), k.boxes.end(), box) != k.boxes.end();
  });
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
    EXPECT_LE(std::abs(k->grasp.position.y()), w.trailer.width / 2 - Geometry{}.plate_half_width());
  }
  EXPECT_GE(tops, 4);
}

TEST(PickCandidates, EveryTopBoxOfTheFrontRowOfACeilingHighWallIsAPickPoint) {
  // D1: 0.5 m cartons in five layers up to 5 cm under the ceiling. From
  // where the arm is at its preferred reach, the top face is out of it; the
  // base stands back until the arm reaches it.
  const sim::ObservationParams obs;
  for (std::uint64_t seed : {1, 2}) {
    const sim::World w = sim::without_masses(sim::generate_world(sim::EnvFamily::kD1, seed));
    double front = 1e9, top = 0;
    for (const auto& b : w.boxes) {
      front = std::min(front, sim::bounds(b).x0);
      top = std::max(top, sim::bounds(b).z1);
    }
    std::vector<PickCandidate> all;
    std::vector<PickRejection> why;
    for (auto h : kHeights)
      for (auto side : kSides)
        for (auto& c :
             pick_candidates(w, sim::analyse(w, obs), sim::make_pick(h, side), obs, robot(), {},
                             plr::sim::home_configuration(8.0), 1000, {}, &why))
          all.push_back(std::move(c));
    int tops = 0;
    for (const auto& b : w.boxes) {
      if (sim::bounds(b).x0 > front + 0.05 || sim::bounds(b).z1 < top - 0.01) continue;
      ++tops;
      const PickCandidate* k = find(all, b.id);
      std::string rejected;
      for (const auto& r : why)
        if (r.box == b.id) rejected += r.why + "; ";
      ASSERT_NE(k, nullptr) << "seed " << seed << " box " << b.id << ": " << rejected;
      const sim::JointVector at = plr::sim::home_configuration(k->base_x);
      EXPECT_FALSE(robot().arm_ik(k->grasp, at).empty());
      EXPECT_FALSE(robot().arm_ik(k->pregrasp, at).empty());
      // Lifted off the box under it, it stays under the ceiling.
      const double lift = k->lift.position.z() - k->grasp.position.z();
      EXPECT_GT(lift, 0.0);
      EXPECT_LE(sim::bounds(b).z1 + lift, w.trailer.height - 0.02 + 1e-9) << "box " << b.id;
    }
    EXPECT_EQ(tops, 4);
  }
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
  // A neighbour standing out 3 cm would leave the face beyond the cups'
  // reach: the plate goes up, its lower edge clear of that one.
  w.boxes[0] = sim::testing::make_box(1, 10.17, 0.0, 0.0, {0.4, 0.4, 0.4});
  const auto up = candidates(w);
  k = find(up, 2);
  ASSERT_NE(k, nullptr);
  EXPECT_EQ(k->boxes, std::vector<std::uint32_t>{2});
  EXPECT_NEAR(k->grasp.position.x(), 10.0 - 0.005, 1e-9);
  EXPECT_GE(k->grasp.position.z() - Geometry{}.plate_half_height(), 0.4);
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

TEST(PickCandidates, ABoxOfALeaningColumnIsLiftedClearOfTheBoxUnderIt) {
  // A column of four leaning 9.4 degrees towards the robot (A1 seed 6): the
  // tilted tops overlap in height by 6.5 cm, more than the usual lift.
  sim::World w = trailer_world();
  const double tilt = 9.4 * M_PI / 180;
  const Eigen::Matrix3d r = Eigen::AngleAxisd(-tilt, Eigen::Vector3d::UnitY()).toRotationMatrix();
  for (std::uint32_t k = 0; k < 4; ++k) {
    sim::Box b = sim::testing::make_box(k + 1, 10.2, 0.0, 0.0);
    b.pose.linear() = r;
    b.pose.translation() = Eigen::Vector3d(10.4, 0.0, 0.0) + (k + 0.5) * 0.4 * r.col(2);
    w.boxes.push_back(b);
  }
  const auto all = candidates(w);
  const PickCandidate* top = find(all, 4);
  ASSERT_NE(top, nullptr);
  const std::uint32_t lowest = *std::min_element(top->boxes.begin(), top->boxes.end());
  ASSERT_GT(lowest, 1u);
  const double lift = top->lift.position.z() - top->grasp.position.z();
  EXPECT_GT(sim::bounds(w.boxes[lowest - 1]).z0 + lift, sim::bounds(w.boxes[lowest - 2]).z1);
}

TEST(PickCandidates, ATurnedBoxHiddenOnOneFaceIsTakenByItsOtherFace) {
  // A box turned 40 degrees in a heap: a lower box stands before the face
  // square to the robot, the other side face looks towards the robot too.
  sim::World w = trailer_world();
  sim::Box turned = sim::testing::make_box(1, 10.3, 0.0, 0.0, {0.4, 0.6, 0.4});
  turned.pose.linear() =
      Eigen::AngleAxisd(40 * M_PI / 180, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  w.boxes.push_back(turned);
  w.boxes.push_back(sim::testing::make_box(2, 9.92, -0.32, 0.0, {0.3, 0.3, 0.3}));
  const auto action = sim::make_pick(sim::Height::kHigh, sim::Side::kCenter);
  const auto all = candidates(w, action);
  const PickCandidate* c = find(all, 1);
  ASSERT_NE(c, nullptr);
  EXPECT_EQ(c->boxes, std::vector<std::uint32_t>{1});
  // The plate faces the other face: turned 50 degrees the other way.
  EXPECT_NEAR(c->grasp.yaw, -50 * M_PI / 180, 1e-6);
}

TEST(PickCandidates, BoxesAboveTheNoseDoNotKeepTheBaseBack) {
  // A box lying on the robot's body beside the turret and one hanging out
  // over the floor before the wall (A1 s2: a box tilted on the arm, 1.3 m
  // up): the lowered nose passes under both, so the base comes as close to
  // the wall as without them.
  sim::World w = trailer_world();
  for (std::uint32_t k = 0; k < 3; ++k)
    w.boxes.push_back(sim::testing::make_box(k + 1, 10.2, 0.0, 0.4 * k));
  const auto obs = sim::testing::small_scene_observation();
  const auto scene = sim::analyse(w, obs);
  const double base_x = 8.0;
  const auto action = sim::make_pick(sim::Height::kMid, sim::Side::kCenter);
  const auto clear = pick_candidates(w, scene, action, obs, robot(), {},
                                     plr::sim::home_configuration(base_x), 1000, {});
  ASSERT_NE(find(clear, 3), nullptr);
  w.boxes.push_back(sim::testing::make_box(9, base_x - 1.3, 0.35, 0.55));
  w.boxes.push_back(sim::testing::make_box(10, 9.5, -0.7, 0.8));
  ASSERT_EQ(boxes_on_robot(w, robot(), plr::sim::home_configuration(base_x)),
            std::vector<std::uint32_t>{9});
  const auto c = pick_candidates(w, scene, action, obs, robot(), {},
                                 plr::sim::home_configuration(base_x), 1000, {});
  ASSERT_NE(find(c, 3), nullptr);
  EXPECT_EQ(find(c, 3)->base_x, find(clear, 3)->base_x);
}

TEST(BoxesOnRobot, ABoxHalfOnTheArmHalfOnTheWallAndWhatLiesOnItRideOnTheRobot) {
  // The arm straight out and level; beside its forearm a column as high as
  // the forearm's top. A box lies across both, another on top of it: the
  // arm carries them (moved, the arm takes them along or drops them).
  sim::JointVector q;
  q << 4.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0;
  std::vector<Eigen::Isometry3d> poses;
  robot().forward_kinematics(q, poses);
  double top = 0;
  for (std::size_t l = 0; l < robot().links().size(); ++l)
    if (robot().links()[l].name == "arm_fore")
      for (const auto& shape : robot().links()[l].shapes)
        top = (poses[l] * shape.origin).translation().z() +
              sim::half_extents(shape, poses[l] * shape.origin).z();
  sim::World w = trailer_world();
  sim::Box column = sim::testing::make_box(1, 5.1, 0.3, 0.0, {0.4, 0.4, top});
  w.boxes.push_back(column);
  w.boxes.push_back(sim::testing::make_box(2, 5.1, 0.1, top + 0.001));
  w.boxes.push_back(sim::testing::make_box(3, 5.1, 0.1, top + 0.402));
  EXPECT_EQ(boxes_on_robot(w, robot(), q), (std::vector<std::uint32_t>{2, 3}));
  // Off the arm (the column alone under it), the box is the wall's.
  w.boxes[1] = sim::testing::make_box(2, 5.1, 0.35, top + 0.001);
  w.boxes[2] = sim::testing::make_box(3, 5.1, 0.35, top + 0.402);
  EXPECT_TRUE(boxes_on_robot(w, robot(), q).empty());
}

TEST(PickCandidates, ABoxRestingOnTheTargetKeepsItInPlace) {
  sim::World w = trailer_world();
  w.boxes.push_back(sim::testing::make_box(1, 10.2, 0.0, 0.0));
  w.boxes.push_back(sim::testing::make_box(2, 10.6, 0.0, 0.4));  // behind and above: not on it
  w.boxes.push_back(sim::testing::make_box(3, 10.2, 0.0, 0.4));  // on it
  // Box 1 is taken only with the box resting on it.
  const auto c = candidates(w);
  ASSERT_FALSE(c.empty());
  for (const auto& k : c) {
    const bool one = std::count(k.boxes.begin(), k.boxes.end(), 1u) > 0;
    const bool three = std::count(k.boxes.begin(), k.boxes.end(), 3u) > 0;
    EXPECT_TRUE(!one || three);
    EXPECT_EQ(std::count(k.boxes.begin(), k.boxes.end(), 2u), 0);
  }
  EXPECT_NE(find(c, 3), nullptr);
}

TEST(BoxesOnLoad, AreThoseRestingOnAHeldBox) {
  sim::World w = trailer_world();
  w.boxes.push_back(sim::testing::make_box(1, 10.2, 0.0, 1.0));  // held
  w.boxes.push_back(sim::testing::make_box(2, 10.3, 0.1, 1.4));  // on it
  w.boxes.push_back(sim::testing::make_box(3, 10.2, 0.5, 1.0));  // beside it
  w.boxes.push_back(sim::testing::make_box(4, 10.2, 0.5, 1.4));  // on the one beside
  w.boxes.push_back(sim::testing::make_box(5, 10.2, 0.0, 0.6));  // under it
  EXPECT_EQ(boxes_on_load(w, {1}), std::vector<std::uint32_t>{2});
  EXPECT_TRUE(boxes_on_load(w, {}).empty());
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

// A low box turned well off the axis: the plate's trailing corner at the
// pre-grasp, not only its centre, stays ahead of the lowered nose's tip.
TEST(PickCandidates, ALowTurnedBoxKeepsThePlatesCornerAheadOfTheNose) {
  sim::World w = trailer_world();
  sim::Box b = sim::testing::make_box(1, 10.2, 0.6, 0.0);
  const double yaw = 0.65;
  b.pose.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  w.boxes.push_back(b);
  const Geometry g;
  const std::vector<PickCandidate> c = candidates(w);
  const PickCandidate* k = find(c, 1);
  ASSERT_NE(k, nullptr);
  const double corner_x = k->pregrasp.position.x() - g.plate_half_width() * std::sin(yaw);
  EXPECT_GE(corner_x, k->base_x + g.conveyor_length + g.nose_clearance - 1e-9);
}

// A neighbour turned 45 degrees stands in the plate's corridor only by its
// axis-aligned bounds (they reach 8 cm out of the face); its outline stays
// behind the face there. A narrow box gives the plate no room to slide away.
TEST(PickCandidates, ATurnedNeighbourOnlyItsBoundsReachIsNotInTheWay) {
  sim::World w = trailer_world();
  w.boxes.push_back(sim::testing::make_box(1, 10.2, 0.0, 0.0, {0.4, 0.3, 0.4}));
  sim::Box turned = sim::testing::make_box(2, 10.2, 0.45, 0.0);
  turned.pose.linear() = Eigen::AngleAxisd(M_PI / 4, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  w.boxes.push_back(turned);
  const std::vector<PickCandidate> c = candidates(w);
  const PickCandidate* k = find(c, 1);
  ASSERT_NE(k, nullptr);
  EXPECT_EQ(k->boxes, std::vector<std::uint32_t>{1});
  EXPECT_NEAR(k->grasp.position.x(), 10.0 - Geometry{}.grasp_gap, 1e-9);
}

// A low box standing 20 cm in front of the face, inside the plate's
// outline, leaves less room than the usual pre-grasp distance: the plate
// comes down nearer the face.
TEST(PickCandidates, ABoxInFrontLeavesANearerPreGrasp) {
  sim::World w = trailer_world();
  w.boxes.push_back(sim::testing::make_box(1, 10.2, 0.0, 0.0));
  w.boxes.push_back(sim::testing::make_box(2, 9.65, 0.2, 0.0, {0.3, 0.4, 0.2}));
  const std::vector<PickCandidate> c = candidates(w);
  const PickCandidate* k = find(c, 1);
  ASSERT_NE(k, nullptr);
  const double approach = (k->grasp.position - k->pregrasp.position).norm();
  EXPECT_LT(approach, Geometry{}.pregrasp_distance);
  EXPECT_LE(k->pregrasp.position.x(), 10.0 - 0.08 + 1e-9);
  // The plate's 5 cm body, behind its surface, stays clear of box 2 (B2
  // seed 2: the pre-grasp went into a box lying in front, and the box behind
  // it, the only one left to pick, was never taken).
  EXPECT_GE(k->pregrasp.position.x() - 0.05, 9.8);
}

TEST(CoveredCups, CountsTheCupsWhoseRimLiesOnTheFace) {
  const Geometry g;                                 // 5 x 4 cups over 0.5 m across, 0.4 m up
  EXPECT_EQ(covered_cups(g, 0.25, 0.2, 0, 0), 20);  // a 0.5 x 0.4 m face takes the whole grid
  // A 0.29 m face: the centred grid puts three columns of its five on it,
  // half a cup pitch off centre two.
  EXPECT_EQ(covered_cups(g, 0.145, 0.145, 0, 0), 6);
  EXPECT_EQ(covered_cups(g, 0.145, 0.145, 0.05, 0), 4);
  EXPECT_EQ(covered_cups(g, 0.145, 0.145, 0.5, 0), 0);
  // Centred on the seam of two 0.45 x 0.35 m faces side by side: two
  // columns of two rows on each.
  EXPECT_EQ(covered_cups(g, 0.225, 0.175, 0.23, 0), 4);
  // Centred on a 0.4 m wide face, no whole cup on the neighbour 1 cm away.
  EXPECT_EQ(covered_cups(g, 0.2, 0.2, 0.41, 0), 0);
}

TEST(PickCandidates, ThePlateGoesWhereItCoversTheMostCups) {
  // A 0.29 m box on the floor: the plate, kept off the floor, covers its two
  // lower rows, three columns centred.
  sim::World w = trailer_world();
  w.boxes.push_back(sim::testing::make_box(1, 6.2, 0.0, 0.0, {0.4, 0.29, 0.29}));
  // 0.29 m: a pile box, mid.
  const auto c = candidates(w, sim::make_pick(sim::Height::kMid, sim::Side::kCenter));
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c[0].cups, 6);
  EXPECT_NEAR(c[0].grasp.position.y(), 0.0, 1e-9);
}

TEST(PickCandidates, AfterAFailedGripOfSeveralTheBoxIsTakenAlone) {
  // Two 0.45 m pile boxes side by side: taken together, unless the grip of
  // one failed (the group's cups shared the pump): then alone, with the most cups.
  sim::World w = trailer_world();
  w.boxes.push_back(sim::testing::make_box(1, 6.2, 0.23, 0.0, {0.45, 0.45, 0.35}));
  w.boxes.push_back(sim::testing::make_box(2, 6.2, -0.23, 0.0, {0.45, 0.45, 0.35}));
  const auto pick = sim::make_pick(sim::Height::kMid, sim::Side::kCenter);
  const auto together = candidates(w, pick);
  ASSERT_FALSE(together.empty());
  EXPECT_EQ(together.front().boxes.size(), 2u);
  const auto alone = candidates(w, pick, 8.0, {}, {1, 2});
  ASSERT_EQ(alone.size(), 2u);
  for (const auto& k : alone) {
    EXPECT_EQ(k.boxes.size(), 1u);
    EXPECT_GE(k.cups, together.front().box_cups.front());
  }
}

// A wall of 0.45 m wide, 0.35 m high boxes: five columns 0.46 m apart (the
// middle one at y = 0; in a 2.5 m trailer the centre third is |y| < 0.417)
// and `rows` rows, front face at x = 6.
sim::World even_wall(int rows) {
  sim::World w = trailer_world();
  std::uint32_t id = 1;
  for (int c = -2; c <= 2; ++c)
    for (int r = 0; r < rows; ++r)
      w.boxes.push_back(
          sim::testing::make_box(id++, 6.225, 0.46 * c, 0.35 * r, {0.45, 0.45, 0.35}));
  return w;
}

TEST(PickCandidates, APickTakesTheBoxesOfItsRegionAndWhatIsStackedOnThem) {
  // Four rows: every top is 1.4 m (mid), the row below 1.05 m (low).
  const sim::World w = even_wall(4);
  const sim::ObservationParams obs = sim::testing::small_scene_observation();
  std::size_t groups = 0, ridden_groups = 0;
  for (auto h : kHeights)
    for (auto side : kSides) {
      const auto action = sim::make_pick(h, side);
      const auto c = candidates(w, action);
      // Nothing is high. The top row comes out with the plate on it; a box of
      // the row below only with the top box resting on it, the plate on their
      // seam. The plate seals on two rows at most: the third row's box comes
      // out with the second (the plate on their seam) and the top box riding
      // on them, after every candidate without a rider; the lowest not at all.
      if (h == sim::Height::kHigh) {
        EXPECT_TRUE(c.empty()) << sim::to_string(action);
        continue;
      }
      EXPECT_FALSE(c.empty()) << sim::to_string(action);
      const double own_top = h == sim::Height::kMid ? 1.4 : 1.05;
      bool ridden = false;
      for (const auto& k : c) {
        ASSERT_EQ(k.boxes.size(), k.box_cups.size());
        EXPECT_TRUE(!ridden || !k.riders.empty()) << "a candidate with a rider comes last";
        ridden = !k.riders.empty();
        if (ridden) {
          ++ridden_groups;
          ASSERT_EQ(h, sim::Height::kLow);
          ASSERT_EQ(k.riders.size(), 1u);
          ASSERT_EQ(k.boxes.size(), 2u);
          auto top_of = [&](std::uint32_t id) {
            return sim::bounds(*std::find_if(w.boxes.begin(), w.boxes.end(),
                                             [&](const sim::Box& x) { return x.id == id; }))
                .z1;
          };
          EXPECT_NEAR(top_of(k.box), 0.7, 1e-9);
          EXPECT_NEAR(top_of(k.boxes[1]), 1.05, 1e-9);
          EXPECT_NEAR(top_of(k.riders[0]), 1.4, 1e-9);
          continue;
        }
        EXPECT_EQ(k.boxes.front(), k.box);
        groups += k.boxes.size() > 1;
        std::size_t own = 0, on_them = 0;
        for (std::size_t i = 0; i < k.boxes.size(); ++i) {
          const auto& b = *std::find_if(w.boxes.begin(), w.boxes.end(),
                                        [&](const sim::Box& x) { return x.id == k.boxes[i]; });
          EXPECT_GT(k.box_cups[i], 0);
          const double top = sim::bounds(b).z1;
          own += std::abs(top - own_top) < 1e-9;
          on_them += std::abs(top - 1.4) < 1e-9 && own_top != 1.4;
          const double y = b.pose.translation().y();
          const double band = obs.side_band * w.trailer.width / 2;
          const auto s = y > band    ? sim::Side::kLeft
                         : y < -band ? sim::Side::kRight
                                     : sim::Side::kCenter;
          EXPECT_EQ(s, side) << sim::to_string(action) << " takes box " << b.id;
        }
        EXPECT_EQ(own + on_them, k.boxes.size()) << sim::to_string(action);
        if (h == sim::Height::kLow) {
          EXPECT_EQ(own, on_them) << "each with the box on it";
        }
      }
    }
  // The middle column is the centre third alone: a single box. Each outer
  // third has two columns, their tops taken together by a plate on their seam.
  const auto centre = candidates(w, sim::make_pick(sim::Height::kMid, sim::Side::kCenter));
  ASSERT_EQ(centre.size(), 1u);
  EXPECT_EQ(centre[0].boxes.size(), 1u);
  for (auto side : {sim::Side::kLeft, sim::Side::kRight}) {
    const auto c = candidates(w, sim::make_pick(sim::Height::kMid, side));
    ASSERT_FALSE(c.empty());
    EXPECT_EQ(c.front().boxes.size(), 2u) << sim::to_string(side);
    EXPECT_EQ(c.front().box_cups, (std::vector<int>{4, 4}));
  }
  EXPECT_GE(groups, 2u);
  EXPECT_GE(ridden_groups, 3u) << "a rider in each third";
}

TEST(PickCandidates, TwoStackedBoxesOfOneClassComeOutTogether) {
  // Two rows (tops 0.35 and 0.7 m, both low): the plate on their seam takes
  // a column whole; the lower box alone has the upper one resting on it.
  const sim::World w = even_wall(2);
  const auto c = candidates(w, sim::make_pick(sim::Height::kLow, sim::Side::kCenter));
  ASSERT_FALSE(c.empty());
  ASSERT_EQ(c.front().boxes.size(), 2u);
  std::vector<std::uint32_t> ids = c.front().boxes;
  std::sort(ids.begin(), ids.end());
  EXPECT_EQ(ids, (std::vector<std::uint32_t>{5, 6}));  // the middle column (c = 0)
  // Lifted together over the nose, pulled out clear of the floor.
  EXPECT_GT(c.front().lift.position.z(), c.front().grasp.position.z());
}

TEST(PickCandidates, ANarrowBoxIsTakenWithTheCupsOverItsNeighboursClosed) {
  // A 0.3 m box in the centre third between wide boxes of the side thirds:
  // the 0.5 m plate cannot keep off them. Its cups over them stay closed,
  // so that only the centre box comes out.
  sim::World w = trailer_world();
  w.boxes.push_back(sim::testing::make_box(1, 6.2, 0.0, 0.0, {0.4, 0.3, 0.35}));
  w.boxes.push_back(sim::testing::make_box(2, 6.2, 0.45, 0.0, {0.4, 0.6, 0.35}));
  w.boxes.push_back(sim::testing::make_box(3, 6.2, -0.45, 0.0, {0.4, 0.6, 0.35}));
  // The boxes are 0.35 m high: a pile of class mid.
  const auto c = candidates(w, sim::make_pick(sim::Height::kMid, sim::Side::kCenter));
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c.front().boxes, std::vector<std::uint32_t>{1});
  const Geometry g;
  const auto& cups = g.cups;
  int open = 0;
  for (int r = 0; r < cups.cups_x; ++r)
    for (int k = 0; k < cups.cups_y; ++k) {
      // Across the plate from its centre (the plate faces +x: across is y).
      const double y =
          c.front().grasp.position.y() + ((k + 0.5) / cups.cups_y - 0.5) * cups.extent.y();
      if (!c.front().cups_open[static_cast<std::size_t>(r * cups.cups_y + k)]) continue;
      ++open;
      EXPECT_LE(std::abs(y), 0.15) << "an open cup over a neighbour, row " << r << " column " << k;
    }
  EXPECT_EQ(open, c.front().cups);
}

TEST(PickCandidates, EachBoxOfARegionWithoutCandidatesSaysWhatHoldsIt) {
  // Pick(mid, right): its one box has a low box standing before its face.
  sim::World w = trailer_world();
  w.boxes.push_back(sim::testing::make_box(3, 6.2, -0.8, 0.0, {0.4, 0.4, 0.35}));
  w.boxes.push_back(sim::testing::make_box(4, 5.95, -0.8, 0.0, {0.1, 0.4, 0.2}));
  const auto obs = sim::testing::small_scene_observation();
  std::vector<PickRejection> rejected;
  const auto c = pick_candidates(w, sim::analyse(w, obs),
                                 sim::make_pick(sim::Height::kMid, sim::Side::kRight), obs, robot(),
                                 Geometry{}, plr::sim::home_configuration(8.0), 10, {}, &rejected);
  EXPECT_TRUE(c.empty());
  ASSERT_FALSE(rejected.empty());
  EXPECT_EQ(rejected.front().box, 3u);
  EXPECT_NE(rejected.front().why.find("box 4"), std::string::npos) << rejected.front().why;
}

TEST(PickCandidates, ATurnedBoxAgainstASideWallIsPulledOutInsideTheTrailer) {
  // Turned 0.25 rad, its face towards the wall: pulled straight back along its face's
  // normal, the load would go into the wall.
  sim::World w = trailer_world();
  for (const double sign : {1.0, -1.0}) {
    w.boxes = {sim::testing::make_box(1, 6.2, sign * 0.9, 0.0, {0.5, 0.5, 0.35})};
    w.boxes[0].pose.linear() = Eigen::AngleAxisd(-sign * 0.25, Eigen::Vector3d::UnitZ()).matrix();
    const auto c = candidates(
        w, sim::make_pick(sim::Height::kMid, sign > 0 ? sim::Side::kLeft : sim::Side::kRight));
    ASSERT_EQ(c.size(), 1u);
    const auto b = sim::bounds(w.boxes[0]);
    const double moved = c.front().retract.position.y() - c.front().grasp.position.y();
    EXPECT_LE(b.y1 + moved, w.trailer.width / 2) << sign;
    EXPECT_GE(b.y0 + moved, -w.trailer.width / 2) << sign;
    EXPECT_LT(c.front().retract.position.x(), c.front().lift.position.x() - 0.4);
  }
}

// A box against a side wall is lifted and pulled out away from the wall, but
// no further than halfway to the box beside it: 3 cm into a neighbour 4 mm
// away, every IK solution of the lift collided with it (C s12, boxes 60 and
// 55). Without the neighbour it moves off the wall as before.
TEST(PickCandidates, ABoxAgainstASideWallIsNotLiftedIntoItsNeighbour) {
  sim::World w = trailer_world();
  const double half = w.trailer.width / 2;
  for (const double sign : {1.0, -1.0}) {
    const sim::Box at_wall =
        sim::testing::make_box(1, 6.3, sign * (half - 0.301), 0.0, {0.55, 0.6, 0.5});
    // Set back 5 cm, out of the cups' reach: not taken with it.
    const sim::Box beside =
        sim::testing::make_box(2, 6.35, sign * (half - 0.605 - 0.15), 0.0, {0.55, 0.3, 0.5});
    for (const bool with_neighbour : {true, false}) {
      w.boxes = {at_wall};
      if (with_neighbour) w.boxes.push_back(beside);
      const auto all = candidates(w);
      const PickCandidate* c = find(all, 1);
      ASSERT_NE(c, nullptr) << sign;
      ASSERT_EQ(c->boxes, std::vector<std::uint32_t>{1}) << sign;
      const double lifted = sign * (c->lift.position.y() - c->grasp.position.y());
      const double pulled = sign * (c->retract.position.y() - c->grasp.position.y());
      if (with_neighbour) {
        const double room = sim::bounds(at_wall).y0 - sim::bounds(beside).y1;
        const double gap = sign > 0 ? room : sim::bounds(beside).y0 - sim::bounds(at_wall).y1;
        EXPECT_GE(lifted, -gap / 2 - 1e-9) << sign;
        EXPECT_GE(pulled, -gap / 2 - 1e-9) << sign;
        EXPECT_LE(lifted, 0.0) << sign;
      } else {
        EXPECT_LT(lifted, -0.02) << sign;
        EXPECT_LT(pulled, -0.02) << sign;
      }
    }
  }
}

TEST(PickCandidates, ATurnedBoxBesideASideWallIsApproachedWithThePlateInsideTheTrailer) {
  // Turned 0.2 rad, its face towards the wall: backed off along the face's
  // normal to the pre-grasp, a plate at the wall would go into it.
  sim::World w = trailer_world();
  for (const double sign : {1.0, -1.0}) {
    w.boxes = {sim::testing::make_box(1, 6.2, sign * 0.97, 0.0, {0.3, 0.3, 0.28})};
    w.boxes[0].pose.linear() = Eigen::AngleAxisd(-sign * 0.2, Eigen::Vector3d::UnitZ()).matrix();
    const auto c = candidates(
        w, sim::make_pick(sim::Height::kMid, sign > 0 ? sim::Side::kLeft : sim::Side::kRight));
    ASSERT_EQ(c.size(), 1u) << sign;
    const Geometry g;
    for (const sim::PlateTarget& t : {c.front().pregrasp, c.front().grasp}) {
      const Eigen::Vector2d n(std::cos(t.yaw), std::sin(t.yaw)), across(-n.y(), n.x());
      for (const double a : {-1.0, 1.0})
        for (const double back : {0.0, 0.05}) {  // the plate's surface and its body's back
          const double y = t.position.y() + a * g.plate_half_width() * across.y() - back * n.y();
          EXPECT_LE(std::abs(y), w.trailer.width / 2) << sign;
        }
    }
  }
}

TEST(DropOff, PlacesHoldTheBoxOverTheConveyorAndTurnTheWristSideways) {
  sim::World w = trailer_world();
  w.boxes.push_back(sim::testing::make_box(7, 6.0, 0.0, 1.0, {0.45, 0.55, 0.35}));
  const Geometry g;
  const sim::JointVector at = plr::sim::home_configuration(5.0);
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
  const sim::JointVector q = plr::sim::home_configuration(5.0);
  const sim::PlateTarget here = robot().plate_target(q);
  const Eigen::Vector3d ahead = here.position + Eigen::Vector3d(0.3, 0.0, 0.0);
  EXPECT_TRUE(follows_lines(robot(), q, {{ahead, 0.0}, {here.position, 0.0}}));
  EXPECT_FALSE(follows_lines(robot(), q, {{here.position + Eigen::Vector3d(3.0, 0, 0), 0.0}}));
}

}  // namespace
}  // namespace plr::actions
