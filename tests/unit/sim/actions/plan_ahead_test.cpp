// Planning while moving (ActionOptions::plan_while_moving): the step after a
// motion is planned while the motion runs, from its predicted end state, and
// used only when the state observed afterwards is the predicted one; the
// robot then waits only for the modelled planning the motion did not cover.
#include <gtest/gtest.h>

#include "scene.hpp"

namespace plr::actions {
namespace {

using sim::Height;
using sim::Side;

using namespace testing;

ActionOptions with_plan_ahead(bool on) {
  ActionOptions o = options();
  o.plan_while_moving = on;
  return o;
}

// The modelled planning of every query the outcome kept.
double modelled(const Outcome& out, const PlanTimeModel& model) {
  double s = 0.0;
  for (const auto& q : out.queries) s += model.seconds(q.mode, q.expansions);
  return s;
}

// A box hanging 1 m above the floor behind the wall: it falls while the
// robot's first motion runs, so the world after it is not the predicted one.
sim::World wall_and_a_falling_box(double z0) {
  sim::World w = wall(5.0, 3, 2);
  w.boxes.push_back(box(100, 7.0, 0.8, z0));
  return w;
}

double height_of(const sim::World& w, std::uint32_t id) {
  for (const auto& b : w.boxes)
    if (b.id == id) return b.pose.translation().z();
  return -1.0;
}

TEST(PlanAhead, TheSameStateIsTheOneWithinItsTolerances) {
  Perceived predicted;
  predicted.world = wall(5.0, 2, 1);
  predicted.held = {2};
  EXPECT_TRUE(PlanAhead::same_state(predicted, predicted));
  Perceived seen = predicted;
  seen.world.boxes[0].pose.translation().x() += 0.5 * PlanAhead::kBoxShift;
  seen.q[sim::kArm2] += 0.5 * PlanAhead::kJoints;
  EXPECT_TRUE(PlanAhead::same_state(predicted, seen));
  seen.world.boxes[0].pose.translation().z() -= 2 * PlanAhead::kBoxShift;  // it fell
  EXPECT_FALSE(PlanAhead::same_state(predicted, seen));
  seen = predicted;
  seen.world.boxes[1].pose.rotate(
      Eigen::AngleAxisd(2 * PlanAhead::kBoxTurn, Eigen::Vector3d::UnitZ()));
  EXPECT_FALSE(PlanAhead::same_state(predicted, seen));
  seen = predicted;
  seen.q[sim::kBaseX] += 2 * PlanAhead::kJoints;  // the base stopped short
  EXPECT_FALSE(PlanAhead::same_state(predicted, seen));
  seen = predicted;
  seen.held.clear();  // the load dropped
  EXPECT_FALSE(PlanAhead::same_state(predicted, seen));
  seen = predicted;
  seen.world.boxes.pop_back();  // a box left
  EXPECT_FALSE(PlanAhead::same_state(predicted, seen));
}

// The nose-down step is planned while the base drives to the pick point;
// the box that fell meanwhile makes the world another one than predicted:
// that plan is not used, the step is planned again from what is observed.
// Later steps, with the box at rest, use theirs.
TEST(PlanAhead, APlanMadeDuringAMotionWhoseEndDiffersFromThePredictionIsNotUsed) {
  const sim::World w = wall_and_a_falling_box(1.0);
  const ActionModel model(robot(), with_plan_ahead(true));
  Fixture f(w);
  const auto out = model.run(sim::make_pick(Height::kLow, Side::kCenter), f.backend, f.memory);
  ASSERT_TRUE(out) << out.error().message;
  EXPECT_LT(height_of(f.simulation.truth(), 100), 0.5);  // it fell
  EXPECT_GE(out->boxes, 1u);
  ASSERT_GE(out->queries.size(), 2u);
  EXPECT_EQ(out->queries[0].mode, planning::PlanMode::kBaseLine);
  EXPECT_EQ(out->queries[1].mode, planning::PlanMode::kNose);
  EXPECT_FALSE(out->queries[1].planned_ahead);
  EXPECT_GT(out->plans_ahead, out->plans_ahead_used);
  EXPECT_GT(out->plans_ahead_used, 0u);
}

// The same world with the box lying on the floor: the state after the
// drive is the predicted one, and the nose-down plan made during it is
// used. What the robot waits for is the modelled planning of the queries
// it used, less what their motions covered.
TEST(PlanAhead, APlanMadeDuringAMotionThatEndsAsPredictedIsUsedAndChargesOnlyTheWait) {
  const sim::World w = wall_and_a_falling_box(0.0);
  const ActionModel model(robot(), with_plan_ahead(true));
  Fixture f(w);
  const auto out = model.run(sim::make_pick(Height::kLow, Side::kCenter), f.backend, f.memory);
  ASSERT_TRUE(out) << out.error().message;
  EXPECT_GE(out->boxes, 1u);
  ASSERT_GE(out->queries.size(), 2u);
  EXPECT_FALSE(out->queries[0].planned_ahead);
  EXPECT_EQ(out->queries[1].mode, planning::PlanMode::kNose);
  EXPECT_TRUE(out->queries[1].planned_ahead);
  EXPECT_GT(out->plans_ahead_used, 0u);
  EXPECT_GT(out->plan_hidden_s, 0.0);
  EXPECT_LE(out->plan_hidden_s, out->exec_s);
  EXPECT_NEAR(out->plan_model_s + out->plan_hidden_s, modelled(*out, model.options().plan_time),
              1e-9);
  EXPECT_DOUBLE_EQ(out->robot_time_s, out->exec_s + out->plan_model_s);

  // Off: every plan is made after the motion before it and charged whole.
  const ActionModel off(robot(), with_plan_ahead(false));
  Fixture g(w);
  const auto waited = off.run(sim::make_pick(Height::kLow, Side::kCenter), g.backend, g.memory);
  ASSERT_TRUE(waited) << waited.error().message;
  EXPECT_EQ(waited->plans_ahead, 0u);
  EXPECT_EQ(waited->plan_hidden_s, 0.0);
  EXPECT_EQ(waited->plan_model_s, modelled(*waited, off.options().plan_time));
  for (const auto& q : waited->queries) EXPECT_FALSE(q.planned_ahead);
}

// Whether a plan made ahead is used depends on the states alone, never on
// which thread finished first: a run repeats to the bit, on a busy machine too.
TEST(PlanAhead, ARunRepeatsBitForBit) {
  const sim::World w = wall(5.0, 3, 2);
  const ActionModel model(robot(), with_plan_ahead(true));
  const std::vector<sim::Action> actions = {sim::make_pick(Height::kLow, Side::kCenter),
                                            sim::make_pick(Height::kMid, Side::kLeft),
                                            sim::make_pick(Height::kLow, Side::kRight)};
  auto run = [&] {
    Fixture f(w);
    std::vector<Outcome> outs;
    for (const auto a : actions) {
      auto out = model.run(a, f.backend, f.memory);
      EXPECT_TRUE(out) << out.error().message;
      if (!out) break;
      outs.push_back(std::move(*out));
    }
    return outs;
  };
  const auto idle = run();
  std::vector<Outcome> busy;
  {
    const CpuLoad load;
    busy = run();
  }
  ASSERT_EQ(idle.size(), actions.size());
  ASSERT_EQ(idle.size(), busy.size());
  std::uint32_t used = 0;
  for (std::size_t i = 0; i < idle.size(); ++i) {
    SCOPED_TRACE(i);
    expect_same_outcome(idle[i], busy[i]);
    used += idle[i].plans_ahead_used;
  }
  EXPECT_GT(used, 0u);
}

}  // namespace
}  // namespace plr::actions
