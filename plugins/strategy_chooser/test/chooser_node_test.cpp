// The chooser plug-in in the fake kernel, with a hand-made library and a
// model trained on hand-made worlds (walls: the library strategy wins;
// piles: H wins), and H served by the test as strategy/hardcoded.
#include <gtest/gtest.h>
#include <unistd.h>
#include <plr/testing/fake_kernel.hpp>

#include <filesystem>
#include <fstream>

#include "plr/chooser/model.hpp"
#include "plr/sim/library.hpp"
#include "plr/sim/testing/worlds.hpp"

namespace plr {
namespace {

namespace fs = std::filesystem;
using testing::FakeKernel;
using testing::NodeOptions;

void add_box(sim::World& w, double x0, double x1, double y0, double y1, double z0, double z1) {
  sim::Box b;
  b.id = static_cast<std::uint32_t>(w.boxes.size() + 1);
  b.size = {x1 - x0, y1 - y0, z1 - z0};
  b.pose.translation() = Eigen::Vector3d((x0 + x1) / 2, (y0 + y1) / 2, (z0 + z1) / 2);
  w.boxes.push_back(b);
}
sim::World wall(double height, double x) {
  sim::World w;
  for (int c = 0; c < 5; ++c)
    for (double z = 0; z < height - 1e-9; z += 0.5)
      add_box(w, x, x + 0.5, -1.25 + 0.5 * c, -0.75 + 0.5 * c, z, z + 0.5);
  return w;
}
sim::World pile(double depth, double x) {
  sim::World w;
  for (double d = 0; d < depth - 1e-9; d += 0.5)
    add_box(w, x + d, x + d + 0.5, -0.75, 0.75, 0.0, 0.4);
  return w;
}

class Chooser : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::path(::testing::TempDir()) / ("plr_chooser_node_" + std::to_string(getpid()));
    fs::create_directories(dir_);
    for (const auto& [name, world, action] :
         {std::tuple{"wall", wall(2.0, 8.0),
                     sim::make_pick(sim::Height::kHigh, sim::Side::kCenter)},
          {"pile", pile(1.5, 6.0), sim::make_sweep(sim::Height::kLow)}}) {
      sim::LibraryEntry e;
      e.name = name;
      e.world = world;
      e.strategy = sim::single_action(action, name);
      library_.entries.push_back(e);
    }
    ASSERT_TRUE(sim::save_library(library_, dir_ / "library.plrl"));
    std::vector<chooser::Features> x;
    std::vector<int> y;
    for (double h : {1.5, 2.0, 2.5}) {
      for (double at : {6.0, 8.0, 10.0}) {
        x.push_back(chooser::features(wall(h, at)));
        y.push_back(chooser::kNearestLabel);
        x.push_back(chooser::features(pile(h - 0.5, at)));
        y.push_back(chooser::kHardcodedLabel);
      }
    }
    auto m = chooser::Model::train(x, y, chooser::Scaling::fit(x), chooser::fingerprint(library_));
    ASSERT_TRUE(m) << m.error().message;
    ASSERT_TRUE(m->save(dir_ / "model.plrm"));
    kernel_.fake_service<msg::NextStrategyRequest, msg::NextStrategyReply>(
        "strategy/hardcoded",
        [](const msg::NextStrategyRequest&, flatbuffers::FlatBufferBuilder& fbb) -> Status {
          const auto s = sim::single_action(sim::Action::PickLowLeft, "H");
          fbb.Finish(
              msg::CreateNextStrategyReply(fbb, sim::build(fbb, s), fbb.CreateString("hardcoded")));
          return {};
        });
  }
  void TearDown() override { fs::remove_all(dir_); }

  Status start(const fs::path& model) {
    const nlohmann::json params = {{"library", (dir_ / "library.plrl").string()},
                                   {"model", model.string()}};
    auto n = kernel_.load_node(STRATEGY_CHOOSER_SO, NodeOptions().with_params(params.dump()));
    if (!n) return n.error();
    node_ = *n;
    return node_->configure();
  }

  Expected<Message<msg::NextStrategyReply>> ask(const sim::World& w) {
    const auto world = sim::testing::world_bytes(w);
    const std::vector<msg::Action> excluded;
    flatbuffers::FlatBufferBuilder fbb;
    fbb.Finish(msg::CreateNextStrategyRequestDirect(fbb, &world, msg::Observation::WallHighLeft,
                                                    &excluded));
    return kernel_.call<msg::NextStrategyRequest, msg::NextStrategyReply>("strategy/next", fbb);
  }

  fs::path dir_;
  sim::Library library_;
  FakeKernel kernel_;
  std::optional<testing::NodeHandle> node_;
};

TEST_F(Chooser, AWallGetsTheNearestLibraryStrategyWithItsReasons) {
  ASSERT_TRUE(start(dir_ / "model.plrm"));
  ASSERT_TRUE(node_->activate());
  auto reply = ask(wall(2.2, 9.0));
  ASSERT_TRUE(reply) << reply.error().message;
  EXPECT_EQ(reply.value()->source()->str(), "library:wall");
  EXPECT_GT(reply.value()->margin(), 0.0);
  EXPECT_GT(reply.value()->distance(), 0.0);
  EXPECT_NE(reply.value()->reason()->str().find("margin"), std::string::npos);
  const auto s = sim::from_message(*reply.value()->strategy(), "reply").value();
  EXPECT_EQ(s.nodes[s.root].action, sim::make_pick(sim::Height::kHigh, sim::Side::kCenter));
  EXPECT_TRUE(kernel_.requests("strategy/hardcoded").empty());
}

TEST_F(Chooser, APileGoesToHThroughTheBus) {
  ASSERT_TRUE(start(dir_ / "model.plrm"));
  ASSERT_TRUE(node_->activate());
  auto reply = ask(pile(1.0, 7.0));
  ASSERT_TRUE(reply) << reply.error().message;
  EXPECT_EQ(reply.value()->source()->str(), "hardcoded");
  EXPECT_LT(reply.value()->margin(), 0.0);
  const auto s = sim::from_message(*reply.value()->strategy(), "reply").value();
  EXPECT_EQ(s.nodes[s.root].action, sim::Action::PickLowLeft);
  EXPECT_EQ(kernel_.requests("strategy/hardcoded").size(), 1u);
}

TEST_F(Chooser, AModelOfAnotherLibraryIsRefused) {
  library_.entries.pop_back();
  ASSERT_TRUE(sim::save_library(library_, dir_ / "library.plrl"));
  const auto s = start(dir_ / "model.plrm");
  ASSERT_FALSE(s);
  EXPECT_NE(s.error().message.find("param 'model': trained with another library"),
            std::string::npos)
      << s.error().message;
}

TEST_F(Chooser, ACorruptModelIsRefusedNamingTheFile) {
  std::fstream f(dir_ / "model.plrm", std::ios::in | std::ios::out | std::ios::binary);
  f.seekp(40);
  f.put('\x7f');
  f.close();
  const auto s = start(dir_ / "model.plrm");
  ASSERT_FALSE(s);
  EXPECT_NE(
      s.error().message.find("param 'model': " + (dir_ / "model.plrm").string() + ": bytes 4.."),
      std::string::npos)
      << s.error().message;
}

}  // namespace
}  // namespace plr
