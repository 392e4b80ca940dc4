// The action model in-process (sim/actions/action_model.cpp, in_process.cpp):
// real physics, the real lattice planner, hand-made worlds.
#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <string>
#include <vector>

#include "plr/sim/generators.hpp"
#include "plr/sim/physics.hpp"

#include "scene.hpp"

namespace plr::actions {
namespace {

using sim::Height;
using sim::Side;

using namespace testing;

TEST(ActionModel, APickTakesABoxOutOfAWall) {
  Fixture f(wall(5.0, 3, 2));
  const ActionModel model(robot(), options());
  const auto out = model.run(sim::make_pick(Height::kLow, Side::kCenter), f.backend, f.memory);
  ASSERT_TRUE(out) << out.error().message;
  EXPECT_GE(out->boxes, 1u);
  EXPECT_EQ(f.simulation.boxes_unloaded(), out->boxes);
  EXPECT_EQ(out->unloaded_at_s.size(), out->boxes);
  EXPECT_GT(out->exec_s, 5.0);
  EXPECT_GT(out->plan_model_s, 0.0);
  EXPECT_DOUBLE_EQ(out->robot_time_s, out->exec_s + out->plan_model_s);
  EXPECT_FALSE(out->queries.empty());
  for (const auto& q : out->queries) EXPECT_TRUE(q.answered);
}

// A pick whose motions could not be planned (here: a search budget far too
// small for them) is not tried again until another box has left: the same
// queries would fail the same way, each at a whole budget's cost.
TEST(ActionModel, ABoxNoMotionWasPlannedToWaitsUntilAnotherBoxLeaves) {
  // Columns of two at the right, in the centre and at the left.
  sim::World w;
  w.trailer.depth = 8.0;
  std::uint32_t id = 1;
  for (const double y : {-0.82, 0.0, 0.82})
    for (const double z0 : {0.0, 0.4}) w.boxes.push_back(box(id++, 5.0, y, z0));
  Fixture f(w);
  ActionOptions starved_options = options();
  starved_options.plan_expansions = 1;
  const ActionModel starved(robot(), starved_options);
  const sim::Action pick = sim::make_pick(Height::kLow, Side::kCenter);
  const auto first = starved.run(pick, f.backend, f.memory);
  ASSERT_TRUE(first) << first.error().message;
  EXPECT_TRUE(first->applicable);
  EXPECT_EQ(first->boxes, 0u);
  ASSERT_FALSE(f.memory.unreached.empty());
  const auto again = starved.run(pick, f.backend, f.memory);
  ASSERT_TRUE(again) << again.error().message;
  EXPECT_FALSE(again->applicable);
  EXPECT_DOUBLE_EQ(again->robot_time_s, starved_options.not_applicable_s);
  // A box of another region leaves: the pick is tried afresh, with the
  // budget it needs.
  const ActionModel model(robot(), options());
  std::vector<std::string> notes;
  Reporter reporter;
  reporter.note = [&](const std::string& n) { notes.push_back(n); };
  const auto other =
      model.run(sim::make_pick(Height::kLow, Side::kLeft), f.backend, f.memory, reporter);
  ASSERT_TRUE(other) << other.error().message;
  ASSERT_GE(other->boxes, 1u) << ::testing::PrintToString(notes);
  EXPECT_TRUE(f.memory.unreached.empty());
  const auto afresh = model.run(pick, f.backend, f.memory);
  ASSERT_TRUE(afresh) << afresh.error().message;
  EXPECT_GE(afresh->boxes, 1u);
}

// Robot time is the trajectories and a model of planning work: the same
// world and action give the same figures, whatever the machine's load.
TEST(ActionModel, TheSameActionTwiceCostsTheSame) {
  const sim::World w = wall(5.0, 3, 2);
  const ActionModel model(robot(), options());
  Fixture a(w), b(w);
  const auto one = model.run(sim::make_pick(Height::kLow, Side::kLeft), a.backend, a.memory);
  const auto two = model.run(sim::make_pick(Height::kLow, Side::kLeft), b.backend, b.memory);
  ASSERT_TRUE(one && two);
  EXPECT_EQ(one->boxes, two->boxes);
  EXPECT_EQ(one->robot_time_s, two->robot_time_s);
  EXPECT_EQ(one->unloaded_at_s, two->unloaded_at_s);
  ASSERT_EQ(one->queries.size(), two->queries.size());
  for (std::size_t i = 0; i < one->queries.size(); ++i)
    EXPECT_EQ(one->queries[i].expansions, two->queries[i].expansions);
}

// A few actions in a row, once on an idle machine and once with every core
// kept busy: the same curve (boxes over robot time), to the bit.
TEST(ActionModel, TheSameRunUnderCpuLoadGivesTheSameCurve) {
  const sim::World w = wall(5.0, 3, 2);
  const ActionModel model(robot(), options());
  const std::vector<sim::Action> actions = {sim::make_pick(Height::kLow, Side::kCenter),
                                            sim::make_pick(Height::kLow, Side::kLeft),
                                            sim::make_pick(Height::kMid, Side::kRight)};
  auto curve = [&] {
    Fixture f(w);
    std::vector<double> times;
    double t = 0;
    for (const auto a : actions) {
      const auto out = model.run(a, f.backend, f.memory);
      EXPECT_TRUE(out) << out.error().message;
      if (!out) break;
      for (double at : out->unloaded_at_s) times.push_back(t + at);
      t += out->robot_time_s;
    }
    times.push_back(t);
    return times;
  };
  const auto idle = curve();
  std::vector<double> busy;
  {
    const CpuLoad load;
    busy = curve();
  }
  EXPECT_GE(idle.size(), 2u);
  EXPECT_EQ(idle, busy);
}

TEST(ActionModel, ASweepCarriesALowPileOut) {
  sim::World w;
  w.trailer.depth = 8.0;
  // Two rows of loose boxes on the floor, 1.5 m deep.
  std::uint32_t id = 1;
  for (double x : {4.0, 4.45, 4.9})
    for (double y : {-0.6, 0.0, 0.6}) w.boxes.push_back(box(id++, x, y, 0.0, 3.0));
  Fixture f(w);
  const ActionModel model(robot(), options());
  const auto out = model.run(sim::make_sweep(Height::kLow), f.backend, f.memory);
  ASSERT_TRUE(out) << out.error().message;
  EXPECT_GE(out->boxes, 3u);
}

// A wall with a deep box on top overhanging it by 0.4 m towards the robot:
// the raised scoop, driven in past the face it meets halfway up, pushes the
// wall (before, it stopped past the overhang's face, 0.2 m short of the
// wall, and moved nothing).
TEST(ActionModel, AHighSweepUnderAnOverhangReachesTheWall) {
  sim::World w = wall(5.0, 3, 3);
  w.boxes.push_back(box(10, 4.6, 0.0, 1.2));
  w.boxes.back().size = {1.0, 0.4, 0.4};
  w.boxes.back().pose.translation().x() = 5.1;  // x 4.6 to 5.6, resting on the middle column
  Fixture f(w);
  const ActionModel model(robot(), options());
  const auto out = model.run(sim::make_sweep(Height::kHigh), f.backend, f.memory);
  ASSERT_TRUE(out) << out.error().message;
  EXPECT_TRUE(out->applicable);
  EXPECT_GE(out->boxes + out->shifted, 1u);
}

TEST(ActionModel, APickTakesAFlatBoxLyingOnTheFloor) {
  // 10 cm high: the plate comes down to 1.5 cm over the floor, and its
  // lowest cups seal on the box's face.
  sim::World w;
  w.trailer.depth = 8.0;
  w.boxes.push_back(box(1, 5.0, 0.0, 0.0, 4.0));
  w.boxes[0].size = {0.4, 0.5, 0.1};
  w.boxes[0].pose.translation().z() = 0.05;
  Fixture f(w);
  const ActionModel model(robot(), options());
  const auto out = model.run(sim::make_pick(Height::kLow, Side::kCenter), f.backend, f.memory);
  ASSERT_TRUE(out) << out.error().message;
  EXPECT_TRUE(out->applicable) << out->why;
  EXPECT_EQ(out->boxes, 1u);
  EXPECT_EQ(out->robot_trailer_contacts, 0u);
}

// Two columns of two 0.45 m wide, 0.35 m high boxes side by side in the
// centre third, front face at x = 5: one low block the plate seals on whole
// (on the corner of the four, four cups on each box).
sim::World block(double mass) {
  sim::World w;
  w.trailer.depth = 8.0;
  std::uint32_t id = 1;
  for (double y : {-0.23, 0.23})
    for (int r = 0; r < 2; ++r) {
      sim::Box b;
      b.id = id++;
      b.size = {0.45, 0.45, 0.35};
      b.mass = mass;
      b.pose.translation() = Eigen::Vector3d(5.0 + 0.225, y, 0.175 + 0.35 * r);
      w.boxes.push_back(b);
    }
  return w;
}

TEST(ActionModel, APickOfSeveralBoxesHoldsWhenLightAndNotWhenHeavy) {
  const ActionModel model(robot(), options());
  const auto action = sim::make_pick(Height::kLow, Side::kCenter);
  // Light (4 kg): the plate takes the whole block at once and delivers it.
  Fixture light(block(4.0));
  const auto a = model.run(action, light.backend, light.memory);
  ASSERT_TRUE(a) << a.error().message;
  EXPECT_GE(a->boxes, 3u);
  for (const auto& e : light.simulation.physics().suction_events())
    EXPECT_NE(e.kind, sim::SuctionEvent::Kind::kRefused);
  // The same boxes at 35 kg: their sixteen cups share the pump (270 N each
  // of 343 N): some are left or lost.
  sim::World heavy = block(4.0);
  std::vector<std::pair<std::uint32_t, double>> masses;
  for (const auto& b : heavy.boxes) masses.emplace_back(b.id, 35.0);
  ASSERT_TRUE(sim::set_masses(heavy, masses));
  Fixture f(heavy);
  const auto b = model.run(action, f.backend, f.memory);
  ASSERT_TRUE(b) << b.error().message;
  EXPECT_LT(b->boxes, a->boxes);
  int lost = 0;
  for (const auto& e : f.simulation.physics().suction_events()) {
    if (e.kind == sim::SuctionEvent::Kind::kRefused ||
        e.kind == sim::SuctionEvent::Kind::kDropped) {
      ++lost;
      EXPECT_GT(e.load, e.capacity);
    }
  }
  EXPECT_GE(lost, 1);
}

// A column of four 0.35 m boxes, front face at x = 5: its top is mid, the
// box under it low, and a low pick takes that box with the top one resting
// on it (the plate on their seam, two rows of cups on each).
sim::World column(double mass) {
  sim::World w;
  w.trailer.depth = 8.0;
  for (int r = 0; r < 4; ++r) {
    sim::Box b;
    b.id = static_cast<std::uint32_t>(r + 1);
    b.size = {0.45, 0.45, 0.35};
    b.mass = mass;
    b.pose.translation() = Eigen::Vector3d(5.0 + 0.225, 0.0, 0.175 + 0.35 * r);
    w.boxes.push_back(b);
  }
  return w;
}

TEST(ActionModel, AStackTakenWholeHoldsWhenLightAndNotWhenHeavy) {
  const ActionModel model(robot(), options());
  const auto action = sim::make_pick(Height::kLow, Side::kCenter);
  const auto gripped = [](const Fixture& f) {
    std::set<std::uint32_t> ids;
    for (const auto& e : f.simulation.physics().suction_events())
      if (e.kind == sim::SuctionEvent::Kind::kGripped) ids.insert(e.box_id);
    return ids;
  };
  // Light (4 kg): the plate takes the box and the one on it together and
  // carries them to the nose. (Released there, the upper box of a stack may
  // topple back off the belt: at least the lower one leaves.)
  Fixture light(column(4.0));
  const auto a = model.run(action, light.backend, light.memory);
  ASSERT_TRUE(a) << a.error().message;
  ASSERT_TRUE(a->applicable) << a->why;
  EXPECT_EQ(gripped(light), (std::set<std::uint32_t>{3, 4}));
  EXPECT_GE(a->boxes, 1u);
  EXPECT_EQ(a->drops, 0u);
  // At 40 kg each, the six cups on each box lose it as the carry speeds up.
  Fixture heavy(column(40.0));
  const auto b = model.run(action, heavy.backend, heavy.memory);
  ASSERT_TRUE(b) << b.error().message;
  EXPECT_EQ(gripped(heavy), (std::set<std::uint32_t>{3, 4}));
  EXPECT_LT(b->boxes, a->boxes);
  int lost = 0;
  for (const auto& e : heavy.simulation.physics().suction_events())
    if (e.kind == sim::SuctionEvent::Kind::kRefused ||
        e.kind == sim::SuctionEvent::Kind::kDropped) {
      ++lost;
      EXPECT_GT(e.load, e.capacity);
    }
  EXPECT_GE(lost, 1);
}

// A column of five 0.35 m boxes: the top two are mid, the rest low. The low
// pick's only grip is the plate on the seam of the third and fourth boxes
// from the floor, with the top box riding on them, unsealed: its weight is
// on the cups.
TEST(ActionModel, ABoxRidingOnTheLoadWeighsOnTheCups) {
  const ActionModel model(robot(), options());
  const auto action = sim::make_pick(Height::kLow, Side::kCenter);
  auto five = [](double rider_mass) {
    sim::World w = column(4.0);
    sim::Box top = w.boxes.back();
    top.id = 5;
    top.mass = rider_mass;
    top.pose.translation().z() += 0.35;
    w.boxes.push_back(top);
    return w;
  };
  auto run = [&](Fixture& f) {
    const auto out = model.run(action, f.backend, f.memory);
    EXPECT_TRUE(out) << out.error().message;
    EXPECT_TRUE(out->applicable) << out->why;
    std::set<std::uint32_t> gripped;
    bool dropped = false;
    for (const auto& e : f.simulation.physics().suction_events()) {
      gripped.insert(e.box_id);
      if (e.kind == sim::SuctionEvent::Kind::kDropped) {
        dropped = true;
        EXPECT_GT(e.load, e.capacity);
      }
    }
    EXPECT_EQ(gripped, (std::set<std::uint32_t>{3, 4}));
    return std::make_pair(*out, dropped);
  };
  // A light rider comes out with the load: the column is two boxes high
  // after the pick.
  Fixture light(five(4.0));
  const auto [a, light_dropped] = run(light);
  EXPECT_FALSE(light_dropped);
  EXPECT_EQ(a.drops, 0u);
  EXPECT_GE(a.boxes, 1u);
  for (const auto& b : light.simulation.truth().boxes) {
    if (b.id != 5) continue;
    EXPECT_LT(b.pose.translation().x(), 5.0) << "the rider stayed on the column";
  }
  // The same boxes under a 40 kg rider: the cups under it let go.
  Fixture heavy(five(40.0));
  const auto [b, heavy_dropped] = run(heavy);
  EXPECT_TRUE(heavy_dropped);
  EXPECT_GE(b.drops, 1u);
}

// Two boxes dragged onto the arm, one lying on the upper arm and one on top
// of it (a ceiling-high wall, issue 46): both ride on the robot. The arm
// folds with them ignored, so they fall, and the pick goes on; taken for
// the wall's, the upper one refused the fold ("goal: arm_fore - box") and
// every later move of the arm through where it lay.
TEST(ActionModel, BoxesLyingOnTheArmAreShakenOffAndThePickGoesOn) {
  constexpr double kBase = 4.0;
  sim::JointVector q;
  q << kBase, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0;  // arm straight out, level
  std::vector<Eigen::Isometry3d> poses;
  robot().forward_kinematics(q, poses);
  double top = 0;  // of the upper arm
  for (std::size_t l = 0; l < robot().links().size(); ++l)
    if (robot().links()[l].name == "arm_upper")
      for (const auto& shape : robot().links()[l].shapes)
        top = std::max(top, sim::half_extents(shape, poses[l] * shape.origin).z() +
                                (poses[l] * shape.origin).translation().z());
  ASSERT_GT(top, 1.0);
  sim::World w = wall(6.6, 3, 2);
  const std::uint32_t lower = 20, upper = 21;
  w.boxes.push_back(box(lower, kBase + 0.3, 0.0, top + 0.002, 3.0));
  w.boxes.push_back(box(upper, kBase + 0.3, 0.0, top + 0.404, 3.0));
  // The folded arm goes through where the upper box lies.
  sim::JointVector folded = q;
  const auto& clear = options().arm_clear;
  for (int k = 0; k < 4; ++k) folded[sim::kArm1 + k] = clear[static_cast<std::size_t>(k)];
  const auto in_the_way = boxes_touching(w, robot(), folded, {"arm_fore"});
  ASSERT_NE(std::find(in_the_way.begin(), in_the_way.end(), upper), in_the_way.end());
  auto riding = boxes_on_robot(w, robot(), q);
  std::sort(riding.begin(), riding.end());
  EXPECT_EQ(riding, (std::vector<std::uint32_t>{lower, upper}));

  Fixture f(q, w);
  const ActionModel model(robot(), options());
  std::vector<std::string> notes;
  Reporter reporter;
  reporter.note = [&](const std::string& line) { notes.push_back(line); };
  const auto out =
      model.run(sim::make_pick(Height::kLow, Side::kCenter), f.backend, f.memory, reporter);
  ASSERT_TRUE(out) << out.error().message;
  for (const auto& n : notes) EXPECT_EQ(n.find("not planned"), std::string::npos) << n;
  EXPECT_TRUE(out->applicable) << out->why;
  EXPECT_GE(out->boxes, 1u);
  const auto end = f.backend.observe();
  ASSERT_TRUE(end);
  // Cleared: off the robot (onto the belt, or the floor).
  const auto after = boxes_on_robot(end->world, robot(), end->q, end->held);
  EXPECT_EQ(std::count(after.begin(), after.end(), lower), 0);
  EXPECT_EQ(std::count(after.begin(), after.end(), upper), 0);
}

TEST(Outcome, CountsTheBoxesThatMovedOrTurnedButStayed) {
  sim::World before = block(4.0), after = block(4.0);
  ASSERT_GE(before.boxes.size(), 4u);
  EXPECT_EQ(boxes_shifted(before, after), 0u);
  after.boxes[0].pose.translation().x() += 0.04;  // settled a little: not counted
  after.boxes[1].pose.translation().z() -= 0.3;   // fell
  after.boxes[2].pose.linear() =
      Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitY()).toRotationMatrix();  // tipped
  after.boxes.pop_back();                                                   // unloaded: not counted
  EXPECT_EQ(boxes_shifted(before, after), 2u);
}

// Fast fidelity behind the same interface: a pick of a box with nothing on
// it (a flat box on the floor, a column of boxes beside it) unloads the
// same box, takes the same robot time and leaves the same semantic
// observation as full fidelity, and the boxes left stay where full leaves
// them.
TEST(Fidelity, AFastPickOfATopBoxGivesWhatFullDoes) {
  sim::World w = wall(5.6, 1, 2);
  for (sim::Box& b : w.boxes) b.pose.translation().y() = 0.8;
  w.boxes.push_back(box(9, 5.0, 0.0, 0.0, 4.0));
  w.boxes.back().size = {0.4, 0.5, 0.1};
  w.boxes.back().pose.translation().z() = 0.05;
  Fixture full(w), fast(w);
  fast.simulation.set_fidelity(sim::Fidelity::kFast);
  const ActionModel model(robot(), options());
  const auto a = model.run(sim::make_pick(Height::kLow, Side::kCenter), full.backend, full.memory);
  const auto b = model.run(sim::make_pick(Height::kLow, Side::kCenter), fast.backend, fast.memory);
  ASSERT_TRUE(a) << a.error().message;
  ASSERT_TRUE(b) << b.error().message;
  ASSERT_EQ(a->boxes, 1u);
  EXPECT_EQ(b->boxes, a->boxes);
  EXPECT_NEAR(b->robot_time_s, a->robot_time_s, 1e-6);
  const sim::World left_full = full.simulation.truth(), left_fast = fast.simulation.truth();
  ASSERT_EQ(left_full.boxes.size(), 2u);  // the flat box left
  ASSERT_EQ(left_fast.boxes.size(), left_full.boxes.size());
  for (std::size_t i = 0; i < left_full.boxes.size(); ++i) {
    EXPECT_EQ(left_fast.boxes[i].id, left_full.boxes[i].id);
    EXPECT_LT(
        (left_fast.boxes[i].pose.translation() - left_full.boxes[i].pose.translation()).norm(),
        0.01);
  }
  const auto seen = [&](const Fixture& f) {
    const auto scene = sim::analyse(f.simulation.perceived(), options().observation);
    return scene.observation ? sim::to_string(*scene.observation) : std::string("none");
  };
  EXPECT_NE(seen(full), "none");
  EXPECT_EQ(seen(fast), seen(full));
}

// Fast fidelity is deterministic: the same action from the same state twice
// ends in the same state, to the bit.
TEST(Fidelity, AFastActionRepeatsExactly) {
  const sim::World w = wall(5.0, 3, 2);
  Fixture one(w), two(w);
  one.simulation.set_fidelity(sim::Fidelity::kFast);
  two.simulation.set_fidelity(sim::Fidelity::kFast);
  const ActionModel model(robot(), options());
  const auto a = model.run(sim::make_pick(Height::kLow, Side::kCenter), one.backend, one.memory);
  const auto b = model.run(sim::make_pick(Height::kLow, Side::kCenter), two.backend, two.memory);
  ASSERT_TRUE(a) << a.error().message;
  ASSERT_TRUE(b) << b.error().message;
  EXPECT_EQ(a->boxes, b->boxes);
  EXPECT_EQ(a->robot_time_s, b->robot_time_s);
  EXPECT_EQ(one.simulation.physics().snapshot().to_bytes(),
            two.simulation.physics().snapshot().to_bytes());
}

}  // namespace
}  // namespace plr::actions
