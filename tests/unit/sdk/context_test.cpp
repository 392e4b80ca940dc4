// What the typed context adds to the C host table: the logger's levels, the
// pipeline clock, refusals turned into errors at once, quick services, and a
// responder that answers for a request its handler dropped. (The semantics
// the host keeps are the host contract's: testing/host_contract_test.cpp.)
#include <plr/context.hpp>
#include <plr/messages.hpp>
#include <plr/testing/fake_kernel.hpp>

#include <gtest/gtest.h>

namespace plr {
namespace {

using namespace std::chrono_literals;
using msg::DoubleReply;
using msg::DoubleRequest;

flatbuffers::FlatBufferBuilder request(std::int64_t v) {
  flatbuffers::FlatBufferBuilder fbb;
  fbb.Finish(msg::CreateDoubleRequest(fbb, v));
  return fbb;
}

class ContextTest : public ::testing::Test {
 protected:
  testing::FakeKernel k_{testing::KernelOptions{.start_ns = 42, .echo_level = PLR_LOG_ERROR}};
  Context ctx_{k_.test_api()};
};

TEST_F(ContextTest, TheLoggerWritesEachLevelFormatted) {
  ctx_.log().debug("d {}", 1);
  ctx_.log().info("i {}", 2);
  ctx_.log().warn("w {}", 3);
  ctx_.log().error("e {}", 4);
  const auto logs = k_.logs();
  ASSERT_EQ(logs.size(), 4u);
  EXPECT_EQ(logs[0].level, PLR_LOG_DEBUG);
  EXPECT_EQ(logs[0].text, "d 1");
  EXPECT_EQ(logs[3].level, PLR_LOG_ERROR);
  EXPECT_EQ(logs[3].text, "e 4");
  EXPECT_EQ(logs[3].node, "test");
}

TEST_F(ContextTest, TimeIsThePipelineClock) {
  EXPECT_EQ(ctx_.now_ns(), 42);
  k_.advance(1ms);
  EXPECT_EQ(ctx_.now_ns(), 42 + 1'000'000);
  EXPECT_EQ(ctx_.name(), "test");
  EXPECT_TRUE(ctx_.params().json().empty());
}

TEST_F(ContextTest, ARefusedCallIsAFailedFutureAtOnce) {
  auto f = ctx_.call<DoubleRequest, DoubleReply>("nobody", request(1));
  ASSERT_TRUE(f.valid());
  ASSERT_TRUE(f.ready());
  const auto reply = f.get();
  ASSERT_FALSE(reply);
  EXPECT_EQ(reply.error().code, PLR_ERR_UNAVAILABLE);
  EXPECT_EQ(reply.error().message, "call 'nobody' refused");
  f.cancel();  // a no-op once completed
}

TEST_F(ContextTest, AQuickServiceIsProvidedWithItsFlag) {
  ASSERT_TRUE((ctx_.provide<DoubleRequest, DoubleReply>(
      "double",
      [](const Message<DoubleRequest>& req, flatbuffers::FlatBufferBuilder& reply) {
        reply.Finish(msg::CreateDoubleReply(reply, 2 * req->value()));
        return Status{};
      },
      ServiceMode::kQuick)));
  const auto reply = k_.call<DoubleRequest, DoubleReply>("double", request(21));
  ASSERT_TRUE(reply) << reply.error().message;
  EXPECT_EQ(reply.value()->value(), 42);
}

TEST_F(ContextTest, AHandlerThatThrowsLeavesItsResponderToAnswer) {
  ASSERT_TRUE((ctx_.provide_async<DoubleRequest, DoubleReply>(
      "throws", [](const Message<DoubleRequest>&, Responder<DoubleReply>) {
        throw std::runtime_error("handler failed");
      })));
  const auto reply = k_.call<DoubleRequest, DoubleReply>("throws", request(1));
  ASSERT_FALSE(reply);
  EXPECT_EQ(reply.error().code, PLR_ERR_INTERNAL);
  EXPECT_EQ(reply.error().message, "provider dropped the request unanswered");
  EXPECT_EQ(k_.logs().back().text, "service handler threw: handler failed");
}

TEST_F(ContextTest, ARequestThatFailsVerificationIsRejectedAndAnswered) {
  ASSERT_TRUE((ctx_.provide<DoubleRequest, DoubleReply>(
      "double", [](const Message<DoubleRequest>&, flatbuffers::FlatBufferBuilder&) {
        ADD_FAILURE() << "an unverified request reached the handler";
        return Status{};
      })));
  flatbuffers::FlatBufferBuilder garbage;
  garbage.PushBytes(reinterpret_cast<const std::uint8_t*>("\xff\xff\xff\xff\xff\xff\xff\xff"), 8);
  const auto reply = k_.call<DoubleRequest, DoubleReply>("double", garbage);
  ASSERT_FALSE(reply);
  EXPECT_EQ(reply.error().message, "request failed verification");
  EXPECT_EQ(k_.rejections().size(), 1u);
}

}  // namespace
}  // namespace plr
