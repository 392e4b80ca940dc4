// Strategy H as a plug-in in the fake kernel: strategy/next on built worlds.
#include <gtest/gtest.h>
#include <plr/testing/fake_kernel.hpp>

#include "plr/sim/strategy.hpp"
#include "plr/sim/testing/worlds.hpp"

namespace plr {
namespace {

using sim::Action;
using testing::FakeKernel;
using testing::NodeOptions;

class Hardcoded : public ::testing::Test {
 protected:
  void start(const std::string& params =
                 R"({"observation": {"h_pile": 0.55}, "h_min": 0.5, "d_min": 0.5})") {
    auto n = kernel_.load_node(STRATEGY_HARDCODED_SO, NodeOptions().with_params(params));
    ASSERT_TRUE(n) << n.error().message;
    node_ = *n;
    ASSERT_TRUE(node_->configure());
    ASSERT_TRUE(node_->activate());
  }

  Expected<Message<msg::NextStrategyReply>> ask(const std::vector<std::uint8_t>& world,
                                                const std::vector<msg::Action>& excluded = {}) {
    flatbuffers::FlatBufferBuilder fbb;
    fbb.Finish(msg::CreateNextStrategyRequestDirect(fbb, &world, msg::Observation::WallHighLeft,
                                                    &excluded));
    return kernel_.call<msg::NextStrategyRequest, msg::NextStrategyReply>("strategy/next", fbb);
  }

  Action decide(const sim::World& w, const std::vector<Action>& excluded = {}) {
    std::vector<msg::Action> ex(excluded.begin(), excluded.end());
    auto reply = ask(sim::testing::world_bytes(w), ex);
    EXPECT_TRUE(reply) << reply.error().message;
    if (!reply) return Action::PickLowLeft;
    EXPECT_EQ(reply.value()->source()->str(), "hardcoded");
    const auto s = sim::from_message(*reply.value()->strategy(), "reply");
    EXPECT_TRUE(s) << s.error().message;
    if (!s) return Action::PickLowLeft;
    EXPECT_EQ(s->nodes.size(), 1u);
    EXPECT_TRUE(s->nodes[0].children.empty());
    return s->nodes[0].action;
  }

  FakeKernel kernel_;
  std::optional<testing::NodeHandle> node_;
};

TEST_F(Hardcoded, HighWallIsPickedFromTheTop) {
  start();
  sim::World w;
  sim::testing::add_wall(w, 10.0, 5, 6);
  w.boxes.push_back(sim::testing::make_box(99, 10.2, -0.82, 2.4));  // the top box, on the right
  EXPECT_EQ(decide(w), Action::PickHighRight);
}

// Under a chooser, which serves strategy/next itself.
TEST_F(Hardcoded, ServesTheServiceItsParamsName) {
  start(R"({"service": "strategy/hardcoded"})");
  EXPECT_TRUE(kernel_.has_provider("strategy/hardcoded"));
  EXPECT_FALSE(kernel_.has_provider("strategy/next"));
}

TEST_F(Hardcoded, DeepPileIsSwept) {
  start();
  sim::World w;
  sim::testing::add_wall(w, 10.0, 5, 5);
  std::uint32_t id = 100;
  for (double x : {8.9, 9.3, 9.7})
    w.boxes.push_back(sim::testing::make_box(id++, x, 0.0, 0.0, {0.4, 0.4, 0.2}));
  EXPECT_EQ(decide(w), Action::SweepLow);  // d_pile = 1.2 > d_min
  // H has one sweep, along the floor, whatever the pile's height.
  w.boxes.push_back(sim::testing::make_box(id++, 9.3, 0.0, 0.2, {0.4, 0.4, 0.25}));
  EXPECT_EQ(decide(w), Action::SweepLow);
}

// What the executor tried here and moved nothing is not answered again: the
// other sides at the same height, then lower, then the sweeps; all tried,
// H's own choice again.
TEST_F(Hardcoded, ExcludedActionsAreReplacedByTheNextFallback) {
  start();
  sim::World w;
  sim::testing::add_wall(w, 10.0, 5, 5);
  w.boxes.push_back(sim::testing::make_box(99, 10.2, -0.82, 2.0));  // top box, right
  EXPECT_EQ(decide(w), Action::PickHighRight);
  EXPECT_EQ(decide(w, {Action::PickHighRight}), Action::PickHighCenter);
  EXPECT_EQ(decide(w, {Action::PickHighRight, Action::PickHighCenter}), Action::PickHighLeft);
  EXPECT_EQ(decide(w, {Action::PickHighRight, Action::PickHighCenter, Action::PickHighLeft}),
            Action::PickMidRight);
  std::vector<Action> all;
  for (int a = 0; a < sim::kNumActions; ++a) all.push_back(static_cast<Action>(a));
  all.pop_back();
  EXPECT_EQ(decide(w, all), static_cast<Action>(sim::kNumActions - 1));
  all.push_back(static_cast<Action>(sim::kNumActions - 1));
  EXPECT_EQ(decide(w, all), Action::PickHighRight);
}

TEST_F(Hardcoded, ShallowPileLeavesTheWall) {
  start();
  sim::World w;
  sim::testing::add_wall(w, 10.0, 5, 4);
  w.boxes.push_back(sim::testing::make_box(100, 9.75, 0.0, 0.0, {0.4, 0.4, 0.3}));  // d_pile = 0.4
  EXPECT_EQ(decide(w), Action::PickMidCenter);                                      // 1.6 m wall
}

// Short columns standing level with the wall's face (A2's walls have them)
// are a pile by height (below h_pile, here 0.55 m), 0.8 m deep, but none of
// it lies before the wall: a
// sweep along the floor stops short of the face, and one driven deeper
// brings the wall down. H picks from the wall.
TEST_F(Hardcoded, ShortColumnsLevelWithTheWallArePicked) {
  start();
  sim::World w;
  std::uint32_t id = 1;
  for (double y : {-0.82, -0.41, 0.0, 0.41})
    for (int r = 0; r < 5; ++r) w.boxes.push_back(sim::testing::make_box(id++, 10.2, y, 0.4 * r));
  for (double x : {10.2, 10.6}) w.boxes.push_back(sim::testing::make_box(id++, x, 0.82, 0.0));
  EXPECT_EQ(decide(w), Action::PickMidCenter);  // 2.0 m wall
  // The same columns standing 1 m out, 0.8 m of them before the face: swept.
  for (auto& b : w.boxes)
    if (b.pose.translation().y() > 0.8) b.pose.translation().x() -= 1.0;
  EXPECT_EQ(decide(w), Action::SweepLow);
}

TEST_F(Hardcoded, DMinMovesTheDecision) {
  start(R"({"d_min": 0.3})");
  sim::World w;
  sim::testing::add_wall(w, 10.0, 5, 4);
  w.boxes.push_back(sim::testing::make_box(100, 9.75, 0.0, 0.0, {0.4, 0.4, 0.3}));
  EXPECT_EQ(decide(w), Action::SweepLow);
}

TEST_F(Hardcoded, LowLeftoversArePicked) {
  start(R"({"observation": {"h_pile": 0.3}, "h_min": 0.5})");
  sim::World w;
  sim::testing::add_wall(w, 10.0, 3, 1);  // one row, 0.4 m: a wall (>= h_pile) below h_min
  EXPECT_EQ(decide(w), Action::PickLowCenter);
  // A pile too shallow to sweep in front of it: its top box is picked.
  w.boxes.push_back(sim::testing::make_box(50, 9.5, 0.6, 0.0, {0.2, 0.4, 0.2}));
  EXPECT_EQ(decide(w), Action::PickLowLeft);
}

TEST_F(Hardcoded, RefusesEmptyAndBadWorlds) {
  start();
  auto empty = ask(sim::testing::world_bytes(sim::World{}));
  ASSERT_FALSE(empty);
  EXPECT_EQ(empty.error().code, PLR_ERR_INVALID);
  EXPECT_EQ(empty.error().message, "strategy/next: the trailer is empty");
  auto garbage = ask({1, 2, 3, 4, 5, 6, 7, 8, 9});
  ASSERT_FALSE(garbage);
  EXPECT_EQ(garbage.error().message, "strategy/next: world is not a valid WorldState");
  auto none = ask({});
  ASSERT_FALSE(none);
  EXPECT_EQ(none.error().message, "strategy/next: request carries no world");
}

TEST_F(Hardcoded, RefusesBadThresholds) {
  auto n = kernel_.load_node(STRATEGY_HARDCODED_SO,
                             NodeOptions().with_params(R"({"observation": {"h_pile": -1}})"));
  ASSERT_TRUE(n);
  auto s = n->configure();
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().message, "param 'observation.h_pile': must be > 0");
  auto m = kernel_.load_node(STRATEGY_HARDCODED_SO,
                             NodeOptions().with_name("second").with_params(R"({"d_min": -0.1})"));
  ASSERT_TRUE(m);
  s = m->configure();
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().message, "param 'd_min': must be >= 0");
}

}  // namespace
}  // namespace plr
