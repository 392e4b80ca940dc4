// template_node.so in the SDK's fake kernel: messages in and out, the
// service, a bad parameter. Callbacks run only inside spin(), on this thread.
#include <plr/messages.hpp>
#include <plr/testing/fake_kernel.hpp>

#include <gtest/gtest.h>

namespace {

using plr::msg::Count;
using plr::testing::FakeKernel;
using plr::testing::NodeOptions;

TEST(TemplateNode, ScalesInputAndAnswersScale) {
  FakeKernel kernel;
  auto node = kernel.load_node(TEMPLATE_NODE_SO, NodeOptions().with_params(R"({"gain": 3})"));
  ASSERT_TRUE(node) << node.error().message;
  ASSERT_TRUE(node->configure());
  ASSERT_TRUE(node->activate());

  flatbuffers::FlatBufferBuilder in;
  in.Finish(plr::msg::CreateCount(in, 5));
  ASSERT_TRUE(kernel.publish<Count>("input", in));
  kernel.spin();
  const auto out = kernel.published("scaled");
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].as<Count>()->value(), 15);

  {
    flatbuffers::FlatBufferBuilder request;
    request.Finish(plr::msg::CreateDoubleRequest(request, 4));
    auto reply = kernel.call<plr::msg::DoubleRequest, plr::msg::DoubleReply>("scale", request);
    ASSERT_TRUE(reply) << reply.error().message;
    EXPECT_EQ(reply.value()->value(), 12);
  }

  ASSERT_TRUE(node->deactivate());
  ASSERT_TRUE(node->cleanup());
  node->destroy();
  EXPECT_EQ(kernel.live_messages(), 0);
}

TEST(TemplateNode, RefusesAZeroGain) {
  FakeKernel kernel;
  auto node = kernel.load_node(TEMPLATE_NODE_SO, NodeOptions().with_params(R"({"gain": 0})"));
  ASSERT_TRUE(node) << node.error().message;
  const auto s = node->configure();
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().code, PLR_ERR_INVALID);
  EXPECT_EQ(s.error().message, "param 'gain': must not be 0");
}

}  // namespace
