// The run's rules (exclusions, stops), the reasons given for boxes left, and
// strategy H run in process by the engine to the end of a small trailer.
#include "plr/episode/engine.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <set>

#include "plr/actions/instantiate.hpp"
#include "plr/sim/generators.hpp"
#include "plr/sim/hardcoded_strategy.hpp"
#include "plr/sim/physics.hpp"

#include "scene.hpp"

namespace plr::episode {
namespace {

using namespace plr::actions;
using actions::testing::box;
using actions::testing::CpuLoad;
using actions::testing::Fixture;
using actions::testing::options;
using actions::testing::planner;
using actions::testing::robot;
using actions::testing::wall;

// Strategy H from the backend's state to the end of the run; `on_step`, if
// given, sees each action's outcome.
plr::Expected<Episode> run_hardcoded(const ActionModel& model, Backend& backend,
                                     const sim::HardcodedParams& h, const RunLimits& limits,
                                     std::function<void(const EpisodeStep&)> on_step = {}) {
  struct Steps final : Observer {
    std::function<void(const EpisodeStep&)> f;
    void recorded(const EpisodeStep& s, const Episode&) override {
      if (f) f(s);
    }
  } steps;
  steps.f = std::move(on_step);
  EngineSettings settings;
  settings.limits = limits;
  settings.observers = {&steps};
  return run_episode(model, backend, hardcoded_source(h), std::move(settings));
}

Outcome moved(std::uint32_t boxes) {
  Outcome o;
  o.boxes = boxes;
  return o;
}

Outcome not_applicable() {
  Outcome o;
  o.applicable = false;
  return o;
}

Outcome grip_failed() {
  Outcome o;
  o.failed_grasp = true;
  return o;
}

TEST(RunRules, AnActionThatMovedNothingIsLeftOutUntilProgress) {
  RunRules rules;
  const auto pick = sim::make_pick(sim::Height::kLow, sim::Side::kLeft);
  rules.record(pick, not_applicable());
  EXPECT_TRUE(rules.excluded(pick));
  EXPECT_FALSE(rules.fresh());
  rules.record(sim::Action::SweepLow, moved(0));
  EXPECT_TRUE(rules.excluded(sim::Action::SweepLow));
  // A failed grip is retried: the grip memory makes the next attempt differ.
  const auto mid = sim::make_pick(sim::Height::kMid, sim::Side::kLeft);
  rules.record(mid, grip_failed());
  EXPECT_FALSE(rules.excluded(mid));
  rules.record(mid, moved(2));
  EXPECT_TRUE(rules.fresh());
  EXPECT_FALSE(rules.excluded(pick));
  EXPECT_EQ(rules.actions(), 4u);
}

TEST(RunRules, WhenAllWereTriedAndSomeShiftedBoxesAllAreTriedAgain) {
  // A2 seed 7: a sweep shook five boxes off the robot and moved them, but
  // unloaded none; the low sweep, excluded before, then moved a box.
  RunRules rules;
  Outcome shook = moved(0);
  shook.shifted = 5;
  rules.record(sim::Action::SweepLow, moved(0));
  rules.record(sim::Action::SweepHigh, shook);
  // Within a round, what was tried stays excluded.
  EXPECT_TRUE(rules.excluded(sim::Action::SweepLow));
  EXPECT_TRUE(rules.excluded(sim::Action::SweepHigh));
  auto try_the_rest = [](RunRules& r) {
    std::vector<sim::Action> rest;
    for (int a = 0; a < sim::kNumActions; ++a)
      if (!r.excluded(static_cast<sim::Action>(a))) rest.push_back(static_cast<sim::Action>(a));
    for (const auto a : rest) r.record(a, moved(0));
  };
  try_the_rest(rules);
  EXPECT_TRUE(rules.fresh());
  EXPECT_FALSE(rules.stop(10));
  // A round in which nothing moved ends the run.
  try_the_rest(rules);
  EXPECT_TRUE(rules.stop(10));
  // Rounds that keep shuffling boxes end after kExtraRounds.
  RunRules shuffling;
  for (int round = 0; round < 10 && !shuffling.stop(10); ++round) {
    shuffling.record(sim::Action::SweepHigh, shook);
    try_the_rest(shuffling);
  }
  EXPECT_TRUE(shuffling.stop(10));
  EXPECT_LE(shuffling.actions(), 3u * sim::kNumActions);
}

TEST(RunRules, StopsWhenEmptyAllExcludedIdleOrAtTheLimit) {
  EXPECT_EQ(RunRules().stop(0), "trailer empty");
  EXPECT_FALSE(RunRules().stop(3).has_value());

  RunRules all;
  for (int a = 0; a < sim::kNumActions; ++a)
    all.record(static_cast<sim::Action>(a), not_applicable());
  EXPECT_EQ(all.stop(3), "no action moves a box: all 12 tried since the last progress");

  RunRules idle({0, 3});
  const auto pick = sim::make_pick(sim::Height::kLow, sim::Side::kLeft);
  for (int k = 0; k < 2; ++k) idle.record(pick, grip_failed());
  EXPECT_FALSE(idle.stop(3).has_value());
  idle.record(pick, grip_failed());
  EXPECT_EQ(idle.stop(3), "no progress in 3 actions");

  RunRules limited({2, 0});
  limited.record(pick, moved(1));
  limited.record(pick, moved(1));
  EXPECT_EQ(limited.stop(3), "action limit (2)");
}

const LeftBox& reason_of(const std::vector<LeftBox>& left, std::uint32_t id) {
  const auto it =
      std::find_if(left.begin(), left.end(), [&](const LeftBox& l) { return l.id == id; });
  EXPECT_NE(it, left.end()) << id;
  return *it;
}

TEST(BoxesLeft, EachBoxHasTheReasonItIsLeftFor) {
  // Two columns of two, two deep: the back ones are behind the front ones.
  sim::World w = wall(7.0, 2, 2);
  for (auto b : wall(7.42, 2, 2).boxes) {
    b.id += 10;
    w.boxes.push_back(b);
  }
  // Tilted on an edge: no face the vertical plate seals on.
  sim::Box tilted = box(20, 6.0, 0.8, 0.2);
  tilted.pose.linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitX()).toRotationMatrix();
  w.boxes.push_back(tilted);
  Memory memory;
  memory.grips[1].given_up = true;
  memory.grips[1].why = "too heavy for every grip";
  memory.unreached[2] = "pre-grasp not planned";
  const ActionModel model(robot(), options());
  const auto left = boxes_left(w, home_configuration(), memory, model);
  ASSERT_EQ(left.size(), w.boxes.size());
  EXPECT_EQ(reason_of(left, 1).reason, LeftReason::kGivenUp);
  EXPECT_EQ(reason_of(left, 1).detail, "too heavy for every grip");
  EXPECT_EQ(reason_of(left, 2).reason, LeftReason::kUnplanned);
  EXPECT_EQ(reason_of(left, 20).reason, LeftReason::kNoFace);
  // Box 11 stands behind box 1: pickable alone, blocked here.
  EXPECT_EQ(reason_of(left, 11).reason, LeftReason::kBlocked);
  EXPECT_EQ(reason_of(left, 11).detail, "in front: 1; resting on it: 12");
  const auto counts = count_by_reason(left);
  EXPECT_EQ(counts.at("given up"), 1u);
  EXPECT_EQ(counts.at("no face the plate seals on"), 1u);
}

TEST(BoxesLeft, ABoxNoArmPoseReachesIsOutOfReach) {
  // Wedged against the ceiling of a low container, above the plate's reach.
  sim::World w;
  w.trailer = {2.35, 2.39, 8.0};
  sim::Box high = box(1, 7.0, 0.0, 2.3);
  high.size = {0.4, 0.4, 0.08};
  high.pose.translation().z() = 2.34;
  w.boxes.push_back(high);
  const ActionModel model(robot(), options());
  const auto left = boxes_left(w, home_configuration(), Memory{}, model);
  ASSERT_EQ(left.size(), 1u);
  EXPECT_EQ(left[0].reason, LeftReason::kOutOfReach);
}

TEST(RunHardcoded, UnloadsASmallWall) {
  Fixture f(wall(6.0, 3, 1));
  const ActionModel model(robot(), options());
  int steps = 0;
  const auto e = run_hardcoded(model, f.backend, sim::HardcodedParams{}, {},
                               [&](const EpisodeStep&) { ++steps; });
  ASSERT_TRUE(e) << e.error().message;
  EXPECT_EQ(e->boxes_total, 3u);
  EXPECT_EQ(e->boxes_unloaded, 3u);
  EXPECT_EQ(e->stop_reason, "trailer empty");
  EXPECT_TRUE(e->left.empty());
  EXPECT_EQ(e->robot_trailer_contacts, 0u);
  EXPECT_EQ(static_cast<std::uint64_t>(steps), e->actions);
  EXPECT_GT(e->robot_time_s, 0.0);
}

// A ceiling-high wall (D1's cartons, two columns, two deep, in an 8 m
// trailer): 0.5 m cartons in five layers up to 5 cm under the ceiling. H
// with the families' settings empties it without touching the trailer.
TEST(RunHardcoded, UnloadsACeilingHighWall) {
  sim::CartonWall narrow = sim::carton_wall(sim::EnvFamily::kD1);
  narrow.columns = 2;
  narrow.slabs = 2;
  auto w = sim::make_carton_wall(narrow, 1, sim::Trailer{2.5, 2.7, 8.0});
  ASSERT_TRUE(w) << w.error().message;
  sim::Simulation settle(*w);
  settle.settle(6.0);
  UnloaderSimulation simulation(robot(), settle.world());
  InProcessBackend backend(simulation, planner());
  const ActionModel model(robot(), ActionOptions{});
  const auto e = run_hardcoded(model, backend, sim::HardcodedParams{}, {});
  ASSERT_TRUE(e) << e.error().message;
  EXPECT_EQ(e->boxes_total, 20u);
  EXPECT_EQ(e->boxes_unloaded, 20u) << e->stop_reason;
  EXPECT_TRUE(e->left.empty());
  EXPECT_EQ(e->robot_trailer_contacts, 0u);
}

// A 40 ft ISO container is 2.35 m wide inside and 2.39 m high: the nose
// (2.2 m wide) is lowered between its walls, and the wall is unloaded
// without touching them.
TEST(RunHardcoded, UnloadsAWallInANarrowContainer) {
  sim::World w = wall(6.0, 5, 3);
  w.trailer.width = 2.35;
  w.trailer.height = 2.39;
  Fixture f(w);
  const ActionModel model(robot(), options());
  const auto e = run_hardcoded(model, f.backend, sim::HardcodedParams{}, {});
  ASSERT_TRUE(e) << e.error().message;
  EXPECT_EQ(e->boxes_unloaded, 15u) << e->stop_reason;
  EXPECT_EQ(e->robot_trailer_contacts, 0u);
}

// A box fell onto the robot's body beside the arm's turret (as boxes do
// from a sweep): the body conveyor carries it out, and the wall is unloaded.
// (Before: it stood for the front of the scene, the base kept back from it,
// out of the wall's reach.)
TEST(RunHardcoded, ABoxOnTheTurretIsCarriedOff) {
  sim::World w = wall(6.0, 3, 1);
  sim::JointVector q = home_configuration();
  q[sim::kBaseX] = 2.5;
  w.boxes.push_back(box(9, 2.5 - 1.3, 0.35, 0.55));
  UnloaderSimulation simulation(robot(), w, q);
  InProcessBackend backend(simulation, planner());
  const ActionModel model(robot(), options());
  ASSERT_EQ(boxes_on_robot(simulation.perceived(), robot(), q), std::vector<std::uint32_t>{9});
  const auto e = run_hardcoded(model, backend, sim::HardcodedParams{}, {});
  ASSERT_TRUE(e) << e.error().message;
  EXPECT_EQ(e->boxes_unloaded, 4u) << e->stop_reason;
  EXPECT_TRUE(e->left.empty());
  EXPECT_EQ(e->robot_trailer_contacts, 0u);
}

// A box too heavy for the belt lies on the raised nose (as after a sweep
// that scooped a whole column): it hides the wall from the pick regions and
// keeps the nose's moves from being planned. The run shakes it off first,
// then unloads the wall.
TEST(RunHardcoded, ABoxLyingOnTheNoseIsShakenOffAndTheWallUnloaded) {
  sim::World w = wall(6.0, 3, 1);
  sim::JointVector q = home_configuration();
  q[sim::kBaseX] = 2.5;
  sim::Box heavy = box(9, 2.5 + 0.35, 0.5, 0.62, 200.0);
  heavy.size = {0.5, 0.6, 0.3};
  heavy.pose.translation().z() = 0.62 + 0.15;
  w.boxes.push_back(heavy);
  UnloaderSimulation simulation(robot(), w, q);
  InProcessBackend backend(simulation, planner());
  const ActionModel model(robot(), options());
  ASSERT_EQ(boxes_on_robot(simulation.perceived(), robot(), q), std::vector<std::uint32_t>{9});
  std::vector<std::string> notes;
  const auto e = run_hardcoded(
      model, backend, sim::HardcodedParams{}, {},
      [&](const EpisodeStep& s) { notes.insert(notes.end(), s.notes.begin(), s.notes.end()); });
  ASSERT_TRUE(e) << e.error().message;
  EXPECT_EQ(e->boxes_unloaded, 4u) << e->stop_reason;
  EXPECT_EQ(e->robot_trailer_contacts, 0u);
  EXPECT_TRUE(std::any_of(notes.begin(), notes.end(), [](const std::string& n) {
    return n.find("9 on the robot: shaking it off") != std::string::npos;
  }));
}

// A pile too heavy to sweep out (A2 seed 3 stopped at 0/117 after six
// sweeps that moved nothing): the drive stalls on it, a sweep that unloaded
// nothing is not repeated before a box left, and the boxes are picked instead.
TEST(RunHardcoded, APileNoSweepMovesIsPickedInstead) {
  sim::World w;
  w.trailer.depth = 8.0;
  std::uint32_t id = 1;
  for (double x : {4.0, 4.42, 4.84})
    for (double y : {-0.42, 0.0, 0.42}) w.boxes.push_back(box(id++, x, y, 0.0, 60.0));
  Fixture f(w);
  const ActionModel model(robot(), options());
  std::uint32_t sweeps_unloading_nothing = 0, repeated = 0;
  std::set<sim::Action> idle;  // unloaded nothing since the last box left
  std::string log;
  const auto e =
      run_hardcoded(model, f.backend, sim::HardcodedParams{}, {}, [&](const EpisodeStep& s) {
        log += sim::to_string(s.action) + ": +" + std::to_string(s.outcome.boxes) + "\n";
        for (const auto& n : s.notes) log += "  " + n + "\n";
        const bool out = s.outcome.boxes > 0;
        if (!out && s.outcome.applicable && sim::kind(s.action) == sim::ActionKind::kSweep)
          ++sweeps_unloading_nothing;
        if (idle.count(s.action) > 0) ++repeated;
        if (out)
          idle.clear();
        else
          idle.insert(s.action);
      });
  ASSERT_TRUE(e) << e.error().message;
  EXPECT_GE(sweeps_unloading_nothing, 2u) << log;  // the world is what this test is about
  EXPECT_EQ(repeated, 0u) << log;
  EXPECT_EQ(e->boxes_unloaded, 9u) << e->stop_reason << "\n" << log;
  EXPECT_EQ(e->robot_trailer_contacts, 0u);
}

// A wall set back behind a row of boxes too shallow to sweep (as a partly
// unloaded, stair-stepped wall leaves them; B2 seed 3 stopped at 0/82 after
// six picks at one height found nothing reachable): the nose must stay short
// of the row, and from there no arm pose reaches the wall. H's pick at the
// wall's height is not applicable; the run gives way to the row's height,
// and once the row is out, the wall is in reach.
TEST(RunHardcoded, NothingReachableAtTheFirstHeightGivesWayToAnother) {
  sim::World w = wall(6.2, 3, 3);
  const std::uint32_t wall_boxes = static_cast<std::uint32_t>(w.boxes.size());
  for (double y : {-0.41, 0.0, 0.41})
    w.boxes.push_back(box(static_cast<std::uint32_t>(w.boxes.size() + 1), 4.0, y, 0.0));
  Fixture f(w);
  const ActionModel model(robot(), options());
  const auto seen = f.backend.observe();
  ASSERT_TRUE(seen);
  const auto scene = model.scene(*seen, f.memory);
  const sim::Action first = sim::hardcoded_action(scene, sim::HardcodedParams{});
  ASSERT_EQ(sim::kind(first), sim::ActionKind::kPick);
  std::vector<PickRejection> why;
  EXPECT_TRUE(pick_candidates(seen->world, scene, first, options().observation, robot(), Geometry{},
                              seen->q, 3, {}, &why)
                  .empty());
  ASSERT_FALSE(why.empty());
  for (const auto& r : why) {
    EXPECT_LE(r.box, wall_boxes);
    EXPECT_NE(r.why.find("no arm pose reaches"), std::string::npos) << r.why;
  }
  std::string log;
  const auto e =
      run_hardcoded(model, f.backend, sim::HardcodedParams{}, {}, [&](const EpisodeStep& s) {
        log += sim::to_string(s.action) + ": +" + std::to_string(s.outcome.boxes) + "\n";
      });
  ASSERT_TRUE(e) << e.error().message;
  EXPECT_EQ(e->boxes_unloaded, e->boxes_total) << e->stop_reason << "\n" << log;
  EXPECT_EQ(e->robot_trailer_contacts, 0u);
}

// A box fallen behind the base, wholly behind the robot's front edge (B2
// s2: one lay there after a sweep, and every later sweep and pick planned
// the base back behind it and found no path). It is not part of the scene
// in front: the wall is unloaded from where the robot stands. Then, with
// nothing in front, the base backs out and its rear pushes the box out of
// the door.
TEST(RunHardcoded, ABoxBehindTheRobotIsSetAsideThenPushedOutOfTheDoor) {
  sim::World w = wall(6.0, 3, 2);
  const std::uint32_t behind = static_cast<std::uint32_t>(w.boxes.size() + 1);
  w.boxes.push_back(box(behind, 1.0, 0.0, 0.0));
  sim::JointVector q = home_configuration();
  q[sim::kBaseX] = 3.0;
  UnloaderSimulation simulation(robot(), w, q);
  InProcessBackend backend(simulation, planner());
  const ActionModel model(robot(), options());
  const auto seen = backend.observe();
  ASSERT_TRUE(seen);
  const auto scene = model.scene(*seen, Memory{});
  ASSERT_TRUE(scene.observation);
  EXPECT_EQ(sim::structure(*scene.observation), sim::Structure::kWall);
  EXPECT_EQ(std::count(scene.front_pile.begin(), scene.front_pile.end(), behind), 0);
  std::string log;
  const auto e =
      run_hardcoded(model, backend, sim::HardcodedParams{}, {}, [&](const EpisodeStep& s) {
        log += sim::to_string(s.action) + ": +" + std::to_string(s.outcome.boxes);
        for (const auto& n : s.notes) log += "; " + n;
        log += "\n";
      });
  ASSERT_TRUE(e) << e.error().message;
  EXPECT_EQ(e->boxes_unloaded, e->boxes_total) << e->stop_reason << "\n" << log;
  const auto& out = simulation.physics().unloaded();
  ASSERT_FALSE(out.empty());
  EXPECT_EQ(out.back().box_id, behind) << log;  // the last, once the wall was out
  EXPECT_NE(log.find("backing out to the door"), std::string::npos) << log;
  EXPECT_EQ(e->robot_trailer_contacts, 0u);
}

// A box standing in a side lane against the nose's rear edge, the base at
// the door (A2 s1, after its first back-out). Backing out, the nose pushes
// it ahead: backed out only to where the box stood, the base pushed it by
// its depth each time, and the run stopped with it 22 cm inside the door.
// The back-out itself takes it past the door.
TEST(RunHardcoded, ABoxTheNosePushesIsBackedOutOfTheDoorAtOnce) {
  sim::World w;
  w.trailer.depth = 8.0;
  sim::Box lane;
  lane.id = 1;
  lane.size = {0.46, 0.3, 0.6};
  lane.mass = 8.0;
  lane.pose.translation() = Eigen::Vector3d(1.22, 1.04, 0.3);
  w.boxes.push_back(lane);
  sim::JointVector q = home_configuration();
  q[sim::kBaseX] = 1.47;
  UnloaderSimulation simulation(robot(), w, q);
  InProcessBackend backend(simulation, planner());
  const ActionModel model(robot(), options());
  std::string log;
  int back_outs = 0;
  std::uint32_t out_by_back_out = 0;
  const auto e =
      run_hardcoded(model, backend, sim::HardcodedParams{}, {}, [&](const EpisodeStep& s) {
        log += sim::to_string(s.action) + ": +" + std::to_string(s.outcome.boxes);
        for (const auto& n : s.notes) {
          log += "; " + n;
          if (n.find("backing out") == std::string::npos) continue;
          ++back_outs;
          out_by_back_out += s.outcome.boxes;
        }
        log += "\n";
      });
  ASSERT_TRUE(e) << e.error().message;
  EXPECT_EQ(e->boxes_unloaded, 1u) << e->stop_reason << "\n" << log;
  EXPECT_EQ(back_outs, 1) << log;
  EXPECT_EQ(out_by_back_out, 1u) << log;
  EXPECT_EQ(e->robot_trailer_contacts, 0u);
}

// A box in the side lane against the base's flank, its front end 0.2 m
// ahead of the base's front edge (A2 s9: the belt dropped it there, and
// every move was refused, "start in collision: base_link - box"): the base
// slides past it to the sweep, and the nose comes down with it behind.
TEST(ActionModel, ABoxAgainstTheBasesFlankKeepsNoMoveFromBeingPlanned) {
  sim::World w = wall(6.0, 3, 2);
  sim::Box lane = box(10, 2.8, 0.9225, 0.0);
  lane.size = {0.4, 0.555, 0.3};
  lane.pose.translation().z() = 0.15;
  w.boxes.push_back(lane);
  sim::JointVector q = home_configuration();
  q[sim::kBaseX] = 3.0;
  Fixture f(q, w);
  const ActionModel model(robot(), options());
  std::vector<std::string> notes;
  Reporter reporter;
  reporter.note = [&](const std::string& n) { notes.push_back(n); };
  const auto out = model.run(sim::make_sweep(sim::Height::kMid), f.backend, f.memory, reporter);
  ASSERT_TRUE(out) << out.error().message;
  EXPECT_GE(out->boxes, 1u) << ::testing::PrintToString(notes);
}

// A box left behind the robot's front edge is named so.
TEST(BoxesLeft, ABoxBehindTheRobotsFrontEdgeIsBehindIt) {
  sim::World w = wall(6.0, 1, 1);
  w.boxes.push_back(box(2, 1.0, 0.0, 0.0));
  sim::JointVector q = home_configuration();
  q[sim::kBaseX] = 3.0;
  const ActionModel model(robot(), options());
  const auto left = boxes_left(w, q, Memory{}, model);
  ASSERT_EQ(left.size(), 2u);
  EXPECT_EQ(reason_of(left, 2).reason, LeftReason::kBehind);
  EXPECT_EQ(reason_of(left, 1).reason, LeftReason::kBlocked);
}

// A box wedged under the raised nose (as a shake can leave one) holds the
// base when it backs away to start a sweep: the drive stalls at once. The
// nose lifts off the box and the base backs away to start the sweep.
TEST(ActionModel, ABaseHeldByABoxWedgedUnderTheNoseLiftsTheNoseAndBacksAway) {
  sim::World w = wall(6.0, 3, 1);
  sim::JointVector q = home_configuration();
  q[sim::kBaseX] = 2.5;
  sim::Box wedged = box(9, 2.6, 0.3, 0.0, 20.0);
  wedged.size = {0.5, 0.5, 0.6};
  wedged.pose.translation().z() = 0.3;
  w.boxes.push_back(wedged);
  UnloaderSimulation simulation(robot(), w, q);
  InProcessBackend backend(simulation, planner());
  // Thresholds for full-size boxes: the 0.6 m box is a pile.
  const ActionModel model(robot(), ActionOptions{});
  Memory memory;
  std::vector<std::string> notes;
  Reporter reporter;
  reporter.note = [&](const std::string& n) { notes.push_back(n); };
  const auto out = model.run(sim::make_sweep(sim::Height::kLow), backend, memory, reporter);
  ASSERT_TRUE(out) << out.error().message;
  // Held once, then free: the sweep started short of the box and came back there.
  EXPECT_EQ(std::count_if(notes.begin(), notes.end(),
                          [](const std::string& n) {
                            return n.find("the base stalled") != std::string::npos;
                          }),
            1)
      << ::testing::PrintToString(notes);
  EXPECT_LT(simulation.q()[sim::kBaseX], 1.5);
  EXPECT_EQ(out->robot_trailer_contacts, 0u);
}

// The top box of a column that reaches 2 cm under the ceiling cannot be
// lifted off the box under it, so it cannot be pulled out: it is no pick
// point, and the pick says what holds it. (Before, the lift went into the
// ceiling: each of grip_attempts attempts put it back, about 15 s each,
// before it was given up.) A box given up is tried afresh once a box
// beside it has left the trailer.
TEST(ActionModel, ABoxUnderTheCeilingIsNoPickPointAndAGivenUpBoxIsTriedAfresh) {
  sim::World w;
  w.trailer.depth = 8.0;
  for (std::uint32_t r = 0; r < 6; ++r) w.boxes.push_back(box(r + 1, 6.0, 0.0, 0.4 * r));
  w.boxes.push_back(box(7, 6.0, 0.0, 2.4));
  w.boxes.back().size.z() = 0.28;
  w.boxes.back().pose.translation().z() = 2.4 + 0.14;
  Fixture f(w);
  const ActionModel model(robot(), options());
  std::vector<std::string> notes;
  Reporter reporter;
  reporter.note = [&](const std::string& n) { notes.push_back(n); };
  const auto out = model.run(sim::make_pick(sim::Height::kHigh, sim::Side::kCenter), f.backend,
                             f.memory, reporter);
  ASSERT_TRUE(out) << out.error().message;
  EXPECT_FALSE(out->applicable);
  EXPECT_NE(out->why.find("; 7: box"), std::string::npos) << out->why;
  EXPECT_DOUBLE_EQ(out->robot_time_s, options().not_applicable_s);
  // Given up before, beside a box that has since left (99): tried afresh.
  GripHistory h;
  h.failures = options().grip_attempts;
  h.given_up = true;
  h.neighbours = {6, 99};
  f.memory.grips[7] = h;
  const auto again = model.run(sim::make_pick(sim::Height::kHigh, sim::Side::kCenter), f.backend,
                               f.memory, reporter);
  ASSERT_TRUE(again) << again.error().message;
  EXPECT_FALSE(f.memory.grips.count(7));
  EXPECT_TRUE(std::any_of(notes.begin(), notes.end(), [](const std::string& n) {
    return n.find("box 7 tried afresh") != std::string::npos;
  }));
}

// A slab tilted on its edge (no face the plate seals on) lies from a lower
// box onto the top edge of the box beside it. The candidate rule lets that
// box be taken (the slab slides off what comes out under it); its lift and
// pull-out push the slab aside. (Before: they were planned around the slab
// and failed, as "held box 62 - box 57" did in C s12.)
TEST(ActionModel, ABoxWithATiltedBoxLeaningOnItIsPulledOut) {
  sim::World w;
  w.trailer.depth = 8.0;
  w.boxes.push_back(box(1, 6.0, 0.0, 0.0));
  sim::Box low = box(2, 6.0, -0.41, 0.0);
  low.size.z() = 0.3;
  low.pose.translation().z() = 0.15;
  w.boxes.push_back(low);
  // From box 2's top (z 0.3) up over box 1's edge (y -0.2, z 0.4).
  sim::Box slab = box(3, 6.0, 0.0, 0.0, 2.0);
  slab.size = {0.4, 0.3, 0.06};
  // Its bottom face on box 1's edge 2 cm short of its end: it reaches 2 cm
  // over box 1, under the 3 cm that counts as standing on it.
  const double tilt = std::asin(0.1 / 0.28);
  slab.pose.linear() = Eigen::AngleAxisd(tilt, Eigen::Vector3d::UnitX()).toRotationMatrix();
  slab.pose.translation() =
      Eigen::Vector3d(6.2, -0.2 - 0.03 * std::sin(tilt) - 0.13 * std::cos(tilt),
                      0.4 + 0.03 * std::cos(tilt) - 0.13 * std::sin(tilt));
  w.boxes.push_back(slab);
  ASSERT_FALSE(has_sealable_face(slab));
  Fixture f(w);
  const ActionModel model(robot(), options());
  std::vector<std::string> notes;
  Reporter reporter;
  reporter.note = [&](const std::string& n) { notes.push_back(n); };
  // The pick region that takes box 1 (the slab's high edge makes it a pile).
  const sim::Action pick = sim::make_pick(sim::Height::kHigh, sim::Side::kCenter);
  const auto out = model.run(pick, f.backend, f.memory, reporter);
  ASSERT_TRUE(out) << out.error().message;
  EXPECT_TRUE(out->applicable) << out->why;
  EXPECT_GE(out->boxes, 1u) << ::testing::PrintToString(notes);
  EXPECT_EQ(out->robot_trailer_contacts, 0u);
}

// H's first actions on A1 seed 1, once on an idle machine and once with every
// core kept busy: the same curve (each box's and each action's end in robot
// time) and the same search work, to the bit. One of the M2 queries spends
// its whole budget (seconds of wall time): with a time limit below what the
// budget takes, the busy run's search was cut shorter (A1 seed 1 gave 28.9 s
// and 35.2 s for H's second pick).
TEST(RunHardcoded, TheSameRunOnA1UnderCpuLoadGivesTheSameCurve) {
  ActionOptions o;
  o.plan_expansions = 1500;  // a shorter test; still spent whole by that query
  const ActionModel model(robot(), o);
  const sim::World truth = sim::make_environment(sim::EnvFamily::kA1, 1);
  struct Trace {
    std::vector<double> curve;
    std::vector<std::uint64_t> expansions;
    double plan_model_s = 0, plan_wall_s = 0;
  };
  auto run = [&] {
    UnloaderSimulation simulation(robot(), truth);
    InProcessBackend backend(simulation, planner());
    Trace r;
    double t = 0;
    const auto e = run_hardcoded(model, backend, sim::HardcodedParams{}, RunLimits{3},
                                 [&](const EpisodeStep& s) {
                                   for (double at : s.outcome.unloaded_at_s)
                                     r.curve.push_back(t + at);
                                   t += s.outcome.robot_time_s;
                                   r.curve.push_back(t);
                                   r.plan_model_s += s.outcome.plan_model_s;
                                   r.plan_wall_s += s.outcome.plan_wall_s;
                                   for (const auto& q : s.outcome.queries)
                                     r.expansions.push_back(q.expansions);
                                 });
    EXPECT_TRUE(e) << e.error().message;
    return r;
  };
  const Trace idle = run();
  Trace busy;
  {
    const CpuLoad load;
    busy = run();
  }
  std::printf("planning: modelled %.2f s; measured %.2f s idle, %.2f s busy\n", idle.plan_model_s,
              idle.plan_wall_s, busy.plan_wall_s);
  EXPECT_GE(idle.curve.size(), 3u);
  EXPECT_EQ(idle.curve, busy.curve);
  EXPECT_EQ(idle.expansions, busy.expansions);
  EXPECT_EQ(idle.plan_model_s, busy.plan_model_s);
  EXPECT_TRUE(std::any_of(idle.expansions.begin(), idle.expansions.end(), [&](std::uint64_t n) {
    return n >= o.plan_expansions;
  })) << "no query spent its budget: the test no longer covers the case";
}

}  // namespace
}  // namespace plr::episode
