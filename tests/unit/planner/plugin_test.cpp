// The planner plug-ins in the fake kernel: the "plan" service answers
// PlanRequest with a timed trajectory, and bad requests with their reason.
#include <gtest/gtest.h>

#include <plr/messages.hpp>
#include <plr/testing/fake_kernel.hpp>

namespace plr {
namespace {

using testing::FakeKernel;
using testing::NodeOptions;

class PlanService : public ::testing::TestWithParam<const char*> {
 protected:
  void SetUp() override {
    auto n = kernel_.load_node(GetParam(), NodeOptions().with_params("{}"));
    ASSERT_TRUE(n) << n.error().message;
    node_ = *n;
    ASSERT_TRUE(node_->configure());
    ASSERT_TRUE(node_->activate());
  }

  // Base from x = 1 to x = 2.5 in an empty 16 m trailer (M5).
  Expected<Message<msg::PlanResponse>> call(std::vector<double> start, std::vector<double> goal) {
    flatbuffers::FlatBufferBuilder fbb;
    const msg::Vec3 trailer(2.5, 2.7, 16.0);
    const auto world = msg::CreateWorldStateDirect(fbb, 0, &trailer);
    fbb.Finish(msg::CreatePlanRequestDirect(fbb, msg::PlanMode::M5, &start, &goal, nullptr, false,
                                            5.0, nullptr, world));
    return kernel_.call<msg::PlanRequest, msg::PlanResponse>("plan", fbb);
  }

  FakeKernel kernel_;
  std::optional<testing::NodeHandle> node_;
};

TEST_P(PlanService, PlansABaseMove) {
  const auto reply = call({1.0, 0, -1.0, 2.0, 0.0, 0.5, 0, 0}, {2.5, 0, -1.0, 2.0, 0.0, 0.5, 0, 0});
  ASSERT_TRUE(reply) << reply.error().message;
  const msg::PlanResponse& r = *reply.value();
  ASSERT_EQ(r.status(), msg::PlanStatus::Solved) << r.message()->str();
  const auto* points = r.trajectory()->points();
  ASSERT_GE(points->size(), 2u);
  EXPECT_DOUBLE_EQ(points->Get(0)->positions()->Get(0), 1.0);
  EXPECT_NEAR(points->Get(points->size() - 1)->positions()->Get(0), 2.5, 1e-9);
  // 1.5 m at 0.6 m/s and 0.8 m/s^2.
  EXPECT_NEAR(points->Get(points->size() - 1)->time_s(), 1.5 / 0.6 + 0.6 / 0.8, 1e-9);
}

TEST_P(PlanService, BadRequestNamesTheField) {
  const auto reply = call({1.0, 0, -1.0}, {2.5, 0, -1.0, 2.0, 0.0, 0.5, 0, 0});
  ASSERT_TRUE(reply) << reply.error().message;
  EXPECT_EQ(reply.value()->status(), msg::PlanStatus::InvalidRequest);
  EXPECT_EQ(reply.value()->message()->str(), "PlanRequest.start: needs 8 joint values, got 3");
}

INSTANTIATE_TEST_SUITE_P(Plugins, PlanService,
                         ::testing::Values(PLANNER_ARASTAR_SO, PLANNER_OMPL_SO),
                         [](const auto& info) {
                           return std::string(info.param).find("arastar") != std::string::npos
                                      ? "Arastar"
                                      : "Ompl";
                         });

}  // namespace
}  // namespace plr
