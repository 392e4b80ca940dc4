// PlanRequest/PlanResponse conversion (sim/planning/plan_messages.cpp): a
// query and an answer survive the trip, budgets and stop reasons included,
// and bad fields are named.
#include <gtest/gtest.h>

#include <plr/messages.hpp>

#include "plr/planning/plan_messages.hpp"

namespace plr::planning {
namespace {

using namespace plr::sim;

template <class T>
const T& root(const flatbuffers::FlatBufferBuilder& fbb) {
  return *flatbuffers::GetRoot<T>(fbb.GetBufferPointer());
}

TEST(PlanMessages, AQueryCrossesTheBusWhole) {
  World w;
  w.trailer = {2.35, 2.39, 12.0};
  for (std::uint32_t id : {1u, 2u, 3u}) {
    Box b;
    b.id = id;
    b.pose.translation() = Eigen::Vector3d(5.0 + id, 0.0, 0.2);
    w.boxes.push_back(b);
  }
  PlanQuery q;
  q.mode = PlanMode::kArmBase;
  q.start = plr::sim::home_configuration(1.0);
  q.goal = PoseGoal{{Eigen::Vector3d(4.5, 0.2, 1.1), 0.3}};
  q.time_limit_s = 2.5;
  q.max_expansions = 1234;
  q.eps_initial = 5.0;
  q.eps_final = 1.0;
  q.eps_decrement = 2.0;
  q.held_boxes = {w.boxes[0]};
  q.ignored_boxes = {1, 2};  // 1 is held: it stays; 2 is left out
  flatbuffers::FlatBufferBuilder fbb;
  encode_plan_request(q, w, fbb);
  const auto d = decode_plan_request(root<msg::PlanRequest>(fbb));
  ASSERT_TRUE(d) << d.error().message;
  EXPECT_EQ(d->query.mode, q.mode);
  EXPECT_EQ(d->query.start, q.start);
  const auto& goal = std::get<PoseGoal>(d->query.goal);
  EXPECT_TRUE(goal.target.position.isApprox(Eigen::Vector3d(4.5, 0.2, 1.1)));
  EXPECT_NEAR(goal.target.yaw, 0.3, 1e-12);
  EXPECT_EQ(d->query.time_limit_s, 2.5);
  EXPECT_EQ(d->query.max_expansions, 1234u);
  EXPECT_EQ(d->query.eps_initial, 5.0);
  EXPECT_EQ(d->query.eps_final, 1.0);
  EXPECT_EQ(d->query.eps_decrement, 2.0);
  EXPECT_EQ(d->world.trailer.width, 2.35);
  ASSERT_EQ(d->world.boxes.size(), 2u);
  EXPECT_EQ(d->world.boxes[0].id, 1u);
  EXPECT_EQ(d->world.boxes[1].id, 3u);
  ASSERT_EQ(d->query.held_boxes.size(), 1u);
  EXPECT_EQ(d->query.held_boxes[0].id, 1u);
}

TEST(PlanMessages, BadRequestsNameTheField) {
  msg::PlanRequestT req;
  req.mode = msg::PlanMode::M5;
  req.start = {1.0, 0, -1.0};
  req.world = std::make_unique<msg::WorldStateT>();
  flatbuffers::FlatBufferBuilder fbb;
  fbb.Finish(msg::PlanRequest::Pack(fbb, &req));
  auto d = decode_plan_request(root<msg::PlanRequest>(fbb));
  ASSERT_FALSE(d);
  EXPECT_EQ(d.error().message, "PlanRequest.start: needs 8 joint values, got 3");

  req.start = {1.0, 0, -1.0, 2.0, 0.0, 0.5, 0, 0};
  req.held_box_ids = {42};
  flatbuffers::FlatBufferBuilder held;
  held.Finish(msg::PlanRequest::Pack(held, &req));
  d = decode_plan_request(root<msg::PlanRequest>(held));
  ASSERT_FALSE(d);
  EXPECT_EQ(d.error().message, "PlanRequest.held_box_ids: box 42 is not in the world");
}

TEST(PlanMessages, AnAnswerCrossesBackWithItsStopReasons) {
  PlanResult r;
  r.status = PlanStatus::kSolved;
  r.path = {plr::sim::home_configuration(1.0), plr::sim::home_configuration(2.5)};
  r.trajectory = Trajectory::from_waypoints(r.path, load_robot().value().all_limits());
  r.stats.expansions = 3;
  r.stats.budget_exhausted = true;
  r.stats.escaped = true;
  r.stats.escape_time_s = 0.004;
  flatbuffers::FlatBufferBuilder fbb;
  encode_plan_response(r, "arastar", 0.02, fbb);
  const auto& m = root<msg::PlanResponse>(fbb);
  EXPECT_DOUBLE_EQ(m.stats()->escape_ms(), 4.0);
  const auto d = decode_plan_response(m);
  ASSERT_TRUE(d) << d.error().message;
  EXPECT_EQ(d->status, PlanStatus::kSolved);
  EXPECT_EQ(d->planner, "arastar");
  EXPECT_EQ(d->stats.expansions, 3u);
  EXPECT_TRUE(d->stats.budget_exhausted);
  EXPECT_FALSE(d->stats.time_limit_hit);
  EXPECT_TRUE(d->stats.escaped);
  ASSERT_GE(d->points.size(), 2u);
  EXPECT_EQ(d->points.front().position, plr::sim::home_configuration(1.0));
  EXPECT_EQ(d->points.back().position, plr::sim::home_configuration(2.5));
  EXPECT_NEAR(d->points.back().time_s, r.trajectory.duration(), 1e-12);
  EXPECT_NEAR(d->points[1].time_s, 0.02, 1e-12);
}

}  // namespace
}  // namespace plr::planning
