// The in-process backend (sim/actions/in_process.cpp) keeps one collision
// checker and gives it each query's world: plans and outcomes are those of a
// checker built per query. And UnloaderSimulation::set_masses: the same state
// on another particle of the masses.
#include <gtest/gtest.h>

#include "scene.hpp"

namespace plr::actions {
namespace {

using sim::Height;
using sim::Side;

using namespace testing;

// Several actions in a row, so the kept checker sees boxes leave and move
// between its queries.
TEST(InProcessBackend, AKeptCheckerPlansAsAFreshOnePerQuery) {
  const sim::World w = wall(5.0, 3, 2);
  const ActionModel model(robot(), options());
  Fixture kept(w, {}), fresh(w, InProcessOptions{.reuse_checker = false});
  for (const sim::Action action :
       {sim::make_pick(Height::kLow, Side::kCenter), sim::make_pick(Height::kLow, Side::kLeft),
        sim::make_pick(Height::kLow, Side::kRight)}) {
    SCOPED_TRACE(sim::to_string(action));
    const auto a = model.run(action, kept.backend, kept.memory);
    const auto b = model.run(action, fresh.backend, fresh.memory);
    ASSERT_TRUE(a && b);
    expect_same_outcome(*a, *b);
    EXPECT_EQ(kept.simulation.truth().boxes.size(), fresh.simulation.truth().boxes.size());
  }
  EXPECT_GT(kept.backend.stats().queries, 3u);
  EXPECT_EQ(kept.backend.stats().queries, fresh.backend.stats().queries);
}

// One query straight through the backend, on worlds that change between
// queries: a box on the straight path appears, goes, comes back elsewhere.
// The answers are the same, point for point, as a fresh checker's.
TEST(InProcessBackend, PlansOnChangedWorldsAsAFreshChecker) {
  const sim::World w = wall(4.0, 3, 2);
  UnloaderSimulation simulation(robot(), w);
  InProcessBackend kept(simulation, planner()), fresh(simulation, planner(), {false});
  planning::PlanQuery q;
  q.mode = planning::PlanMode::kArm;
  q.start = simulation.q();
  sim::JointVector goal = q.start;
  goal[sim::kArm1] = 0.3;  // arm turned left and raised
  goal[sim::kArm2] = -0.8;
  goal[sim::kArm3] = 1.6;
  q.goal = planning::JointGoal{goal};
  // The budget, not the clock, ends a search: the same work either way.
  q.max_expansions = 400;
  q.time_limit_s = 60.0;
  // Where the plate passes halfway along the straight joint-space path.
  const Eigen::Vector3d halfway = robot().plate_pose(0.5 * (q.start + goal)).translation();
  std::uint64_t searched = 0;
  for (int round = 0; round < 4; ++round) {
    SCOPED_TRACE(round);
    sim::World world = w;
    if (round % 2 == 1) {
      sim::Box b = box(50 + round, 0, 0, 0);
      b.size = {0.15, 0.15, 0.15};
      b.pose.translation() = halfway + Eigen::Vector3d(0.0, 0.05 * (round - 2), 0.0);
      world.boxes.push_back(b);
    }
    const auto a = kept.plan(q, world), b = fresh.plan(q, world);
    ASSERT_TRUE(a && b);
    if (round % 2 == 0) {
      EXPECT_EQ(a->status, planning::PlanStatus::kSolved) << a->message;
    }
    EXPECT_EQ(a->status, b->status);
    EXPECT_EQ(a->stats.expansions, b->stats.expansions);
    if (round % 2 == 1) searched += a->stats.expansions;
    ASSERT_EQ(a->points.size(), b->points.size());
    for (std::size_t i = 0; i < a->points.size(); ++i)
      EXPECT_EQ(a->points[i].position, b->points[i].position);
  }
  EXPECT_GT(searched, 2u);  // the boxes were in the way
}

// The same state with other masses: the same boxes, heavy, are not carried
// out; given their own masses again, the state repeats the original run.
TEST(UnloaderSimulation, SetMassesChangesOnlyTheMasses) {
  const sim::World w = wall(5.0, 3, 2, 5.0);
  const ActionModel model(robot(), options());
  const sim::Action pick = sim::make_pick(Height::kLow, Side::kCenter);
  Fixture f(w, {});
  const auto start = f.simulation.save();
  const auto light = model.run(pick, f.backend, f.memory);
  ASSERT_TRUE(light) << light.error().message;
  ASSERT_GE(light->boxes, 1u);

  std::vector<std::pair<std::uint32_t, double>> heavy, same;
  for (const sim::Box& b : w.boxes) {
    heavy.emplace_back(b.id, 400.0);
    same.emplace_back(b.id, b.mass);
  }
  f.simulation.restore(*start);
  ASSERT_TRUE(f.simulation.set_masses(heavy).has_value());
  for (const sim::Box& b : f.simulation.truth().boxes) EXPECT_EQ(b.mass, 400.0);
  Memory memory;
  const auto out = model.run(pick, f.backend, memory);
  ASSERT_TRUE(out) << out.error().message;
  EXPECT_EQ(out->boxes, 0u);

  f.simulation.restore(*start);
  ASSERT_TRUE(f.simulation.set_masses(same).has_value());
  Memory again;
  const auto repeat = model.run(pick, f.backend, again);
  ASSERT_TRUE(repeat);
  expect_same_outcome(*light, *repeat);

  const auto unknown = f.simulation.set_masses({{w.boxes[0].id, 3.0}, {9999, 3.0}});
  ASSERT_FALSE(unknown.has_value());
  EXPECT_EQ(unknown.error().message, "set_masses: no box 9999");
  EXPECT_FALSE(f.simulation.set_masses({{w.boxes[0].id, -1.0}}).has_value());
  EXPECT_EQ(f.simulation.truth().boxes[0].mass, 5.0);
}

}  // namespace
}  // namespace plr::actions
