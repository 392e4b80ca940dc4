// The Node base class: state checks before the hooks, errors from the hooks.
#include <plr/node.hpp>
#include <plr/testing/fake_kernel.hpp>

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>
#include <vector>

namespace {

using plr::NodeState;
using plr::testing::FakeKernel;
using plr::testing::NodeOptions;

class Recorder : public plr::Node {
 public:
  using Node::Node;
  std::vector<std::string> calls;
  plr::Status fail_configure;  // returned by on_configure when set to an error
  bool throw_in_activate = false;

 protected:
  plr::Status on_configure() override {
    calls.push_back("configure");
    params().allow_only({"gain"});
    gain_ = params().get<double>("gain", 1.0);
    return fail_configure;
  }
  plr::Status on_activate() override {
    calls.push_back("activate");
    if (throw_in_activate) throw std::runtime_error("device not found");
    return {};
  }
  plr::Status on_deactivate() override {
    calls.push_back("deactivate");
    return {};
  }
  plr::Status on_cleanup() override {
    calls.push_back("cleanup");
    return {};
  }

 private:
  double gain_ = 1.0;
};

TEST(Node, RunsHooksInLifeCycleOrder) {
  FakeKernel k;
  auto h = k.add<Recorder>();
  auto& n = h.get<Recorder>();
  EXPECT_EQ(n.state(), NodeState::Unconfigured);
  ASSERT_TRUE(h.configure());
  EXPECT_EQ(n.state(), NodeState::Configured);
  ASSERT_TRUE(h.activate());
  EXPECT_EQ(n.state(), NodeState::Active);
  ASSERT_TRUE(h.deactivate());
  EXPECT_EQ(n.state(), NodeState::Configured);
  ASSERT_TRUE(h.cleanup());
  EXPECT_EQ(n.state(), NodeState::Unconfigured);
  EXPECT_EQ(n.calls, (std::vector<std::string>{"configure", "activate", "deactivate", "cleanup"}));
}

TEST(Node, RefusesWrongOrderWithoutCallingTheHook) {
  FakeKernel k;
  auto h = k.add<Recorder>();
  auto s = h.activate();
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().code, PLR_ERR_STATE);
  EXPECT_EQ(s.error().message, "activate: node is unconfigured, needs configured");
  s = h.cleanup();
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().message, "cleanup: node is unconfigured, needs configured");
  ASSERT_TRUE(h.configure());
  ASSERT_TRUE(h.activate());
  s = h.configure();
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().code, PLR_ERR_STATE);
  EXPECT_EQ(s.error().message, "configure: node is active, needs unconfigured");
  EXPECT_EQ(h.get<Recorder>().calls, (std::vector<std::string>{"configure", "activate"}));
}

TEST(Node, DeactivateIsANoOpUnlessActive) {
  FakeKernel k;
  auto h = k.add<Recorder>();
  EXPECT_TRUE(h.deactivate());
  ASSERT_TRUE(h.configure());
  EXPECT_TRUE(h.deactivate());
  EXPECT_EQ(h.get<Recorder>().state(), NodeState::Configured);
  EXPECT_EQ(h.get<Recorder>().calls, (std::vector<std::string>{"configure"}));
}

TEST(Node, FailedHookKeepsTheState) {
  FakeKernel k;
  auto h = k.add<Recorder>();
  h.get<Recorder>().fail_configure = plr::make_error(PLR_ERR_UNAVAILABLE, "map server missing");
  auto s = h.configure();
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().code, PLR_ERR_UNAVAILABLE);
  EXPECT_EQ(s.error().message, "map server missing");
  EXPECT_EQ(h.get<Recorder>().state(), NodeState::Unconfigured);
  h.get<Recorder>().fail_configure = {};
  EXPECT_TRUE(h.configure());
}

TEST(Node, ExceptionFromAHookBecomesAnInvalidError) {
  FakeKernel k;
  auto h = k.add<Recorder>();
  h.get<Recorder>().throw_in_activate = true;
  ASSERT_TRUE(h.configure());
  auto s = h.activate();
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().code, PLR_ERR_INVALID);
  EXPECT_EQ(s.error().message, "device not found");
  EXPECT_EQ(h.get<Recorder>().state(), NodeState::Configured);
}

TEST(Node, ParamErrorsFailConfigureWithTheirText) {
  FakeKernel k;
  auto typo = k.add<Recorder>(NodeOptions().with_name("typo").with_params(R"({"gian": 2})"));
  auto s = typo.configure();
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().code, PLR_ERR_INVALID);
  EXPECT_EQ(s.error().message, "param 'gian': unknown parameter");

  auto mistyped =
      k.add<Recorder>(NodeOptions().with_name("mistyped").with_params(R"({"gain": "high"})"));
  s = mistyped.configure();
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().message, "param 'gain': expected a number, got \"high\"");
}

TEST(Node, ContextSeesNameParamsAndClock) {
  FakeKernel k({.start_ns = 1'000, .echo_level = PLR_LOG_WARN});
  auto h = k.add<Recorder>(NodeOptions().with_name("arm_planner").with_params(R"({"gain": 0.5})"));
  // The Context a node reads, seen through the same host table.
  struct Peek : plr::Node {
    using Node::ctx;
    using Node::Node;
  };
  auto p = k.add<Peek>(NodeOptions().with_name("peek").with_params(R"({"x": 1})"));
  auto& ctx = p.get<Peek>().ctx();
  EXPECT_EQ(ctx.name(), "peek");
  EXPECT_EQ(ctx.params().require<int>("x"), 1);
  EXPECT_EQ(ctx.now_ns(), 1'000);
  k.advance(std::chrono::milliseconds(2));
  EXPECT_EQ(ctx.now_ns(), 2'001'000);
  EXPECT_EQ(h.name(), "arm_planner");
}

}  // namespace
