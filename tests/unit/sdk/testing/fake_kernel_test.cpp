// The fake kernel: delivery on spin(), services both ways, the manual clock,
// message accounting, and loading plug-ins by path.
#include <plr/messages.hpp>
#include <plr/node.hpp>
#include <plr/testing/fake_kernel.hpp>

#include <gtest/gtest.h>

#include <optional>
#include <string>

namespace {

using namespace std::chrono_literals;
using plr::Message;
using plr::msg::Count;
using plr::msg::DoubleReply;
using plr::msg::DoubleRequest;
using plr::testing::FakeKernel;
using plr::testing::NodeOptions;

flatbuffers::FlatBufferBuilder count(std::int64_t v) {
  flatbuffers::FlatBufferBuilder fbb;
  fbb.Finish(plr::msg::CreateCount(fbb, v));
  return fbb;
}
flatbuffers::FlatBufferBuilder double_request(std::int64_t v) {
  flatbuffers::FlatBufferBuilder fbb;
  fbb.Finish(plr::msg::CreateDoubleRequest(fbb, v));
  return fbb;
}

// in -> out (value + 1); serves `double`; on `ask` calls `remote` and waits.
class Echo : public plr::Node {
 public:
  using Node::Node;
  std::optional<Message<Count>> last;  // kept to test buffer accounting
  std::optional<plr::Error> remote_error;
  std::int64_t remote_answer = 0;

 protected:
  plr::Status on_configure() override {
    params().allow_only({"factor"});
    factor_ = params().get<std::int64_t>("factor", 2);
    auto out = ctx().advertise<Count>("out");
    if (!out) return out.error();
    out_ = *out;
    if (auto s = ctx().subscribe<Count>("in",
                                        [this](const Message<Count>& m) {
                                          last = m;
                                          (void)out_.publish(count(m->value() + 1));
                                        });
        !s)
      return s;
    if (auto s =
            ctx().subscribe<Count>("ask", [this](const Message<Count>& m) { ask(m->value()); });
        !s)
      return s;
    return ctx().provide<DoubleRequest, DoubleReply>(
        "double", [this](const Message<DoubleRequest>& req, flatbuffers::FlatBufferBuilder& reply) {
          reply.Finish(plr::msg::CreateDoubleReply(reply, req->value() * factor_));
          return plr::Status{};
        });
  }

 private:
  // Blocks in get() inside a callback: fine, since fake services answer at once.
  void ask(std::int64_t v) {
    auto reply = ctx().call<DoubleRequest, DoubleReply>("remote", double_request(v), 1s).get();
    if (reply) {
      remote_answer = reply.value()->value();
      remote_error.reset();
    } else {
      remote_error = reply.error();
    }
  }

  std::int64_t factor_ = 2;
  plr::Publisher<Count> out_;
};

// Serves `slow` and answers only when the test says so.
class Slow : public plr::Node {
 public:
  using Node::Node;
  std::optional<plr::Responder<DoubleReply>> held;

 protected:
  plr::Status on_configure() override {
    return ctx().provide_async<DoubleRequest, DoubleReply>(
        "slow", [this](const Message<DoubleRequest>&, plr::Responder<DoubleReply> r) {
          held.emplace(std::move(r));
        });
  }
};

// A node of type N, added, configured and activated.
template <class N>
plr::testing::NodeHandle active(FakeKernel& k, plr::testing::NodeOptions o = {}) {
  auto h = k.add<N>(std::move(o));
  EXPECT_TRUE(h.configure());
  EXPECT_TRUE(h.activate());
  return h;
}

TEST(FakeKernel, DeliversOnlyWhenSpun) {
  FakeKernel k({.start_ns = 5'000, .echo_level = PLR_LOG_WARN});
  auto echo = active<Echo>(k);
  ASSERT_TRUE(k.publish<Count>("in", count(41)));
  EXPECT_TRUE(k.published("out").empty());
  EXPECT_EQ(k.spin(), 1u);
  const auto out = k.published("out");
  ASSERT_EQ(out.size(), 1u);
  ASSERT_NE(out[0].as<Count>(), nullptr);
  EXPECT_EQ(out[0].as<Count>()->value(), 42);
  EXPECT_EQ(out[0].from, echo.name());
  EXPECT_EQ(out[0].stamp_ns, 5'000);
  EXPECT_EQ(out[0].as<DoubleReply>(), nullptr) << "a sample is only readable as its own type";
}

TEST(FakeKernel, InactiveNodesReceiveNothing) {
  FakeKernel k;
  auto echo = k.add<Echo>();
  ASSERT_TRUE(echo.configure());
  ASSERT_TRUE(k.publish<Count>("in", count(1)));
  k.spin();
  EXPECT_TRUE(k.published("out").empty());
  ASSERT_TRUE(echo.activate());
  ASSERT_TRUE(k.publish<Count>("in", count(2)));
  k.spin();
  ASSERT_EQ(k.published("out").size(), 1u);
  EXPECT_EQ(k.published("out")[0].as<Count>()->value(), 3);
}

TEST(FakeKernel, CleanupDropsTheNodesRegistrations) {
  FakeKernel k;
  auto echo = active<Echo>(k);
  EXPECT_TRUE(k.has_provider("double"));
  EXPECT_EQ(k.subscribers("in"), 1u);
  EXPECT_EQ(k.publishers("out"), 1u);
  ASSERT_TRUE(echo.deactivate());
  ASSERT_TRUE(echo.cleanup());
  EXPECT_FALSE(k.has_provider("double"));
  EXPECT_EQ(k.subscribers("in"), 0u);
  EXPECT_EQ(k.publishers("out"), 0u);
  ASSERT_TRUE(echo.configure()) << "registering again after cleanup must work";
  EXPECT_TRUE(k.has_provider("double"));
}

TEST(FakeKernel, TestCallsANodesService) {
  FakeKernel k;
  active<Echo>(k, NodeOptions().with_params(R"({"factor": 3})"));
  auto reply = k.call<DoubleRequest, DoubleReply>("double", double_request(7));
  ASSERT_TRUE(reply) << reply.error().message;
  EXPECT_EQ(reply.value()->value(), 21);
  ASSERT_EQ(k.requests("double").size(), 1u);
  EXPECT_EQ(k.requests("double")[0].as<DoubleRequest>()->value(), 7);
}

// A quick service (ServiceMode::kQuick) is provided through ABI 1.1's
// provide_flags; the fake kernel answers it like any other.
class QuickDoubler : public plr::Node {
 public:
  using Node::Node;

 protected:
  plr::Status on_configure() override {
    return ctx().provide<DoubleRequest, DoubleReply>(
        "quick_double",
        [](const Message<DoubleRequest>& req, flatbuffers::FlatBufferBuilder& reply) {
          reply.Finish(plr::msg::CreateDoubleReply(reply, 2 * req->value()));
          return plr::Status{};
        },
        plr::ServiceMode::kQuick);
  }
};

TEST(FakeKernel, QuickServicesAreAnswered) {
  FakeKernel k;
  active<QuickDoubler>(k);
  auto reply = k.call<DoubleRequest, DoubleReply>("quick_double", double_request(4));
  ASSERT_TRUE(reply) << reply.error().message;
  EXPECT_EQ(reply.value()->value(), 8);
}

TEST(FakeKernel, CallWithoutProviderFailsWithItsName) {
  FakeKernel k;
  auto reply = k.call<DoubleRequest, DoubleReply>("nope", double_request(1));
  ASSERT_FALSE(reply);
  EXPECT_EQ(reply.error().code, PLR_ERR_UNAVAILABLE);
  EXPECT_EQ(reply.error().message, "no provider for service 'nope'");
}

TEST(FakeKernel, NodeCallWithoutProviderIsRefused) {
  FakeKernel k;
  auto echo = active<Echo>(k);
  ASSERT_TRUE(k.publish<Count>("ask", count(4)));
  k.spin();
  ASSERT_TRUE(echo.get<Echo>().remote_error.has_value());
  EXPECT_EQ(echo.get<Echo>().remote_error->code, PLR_ERR_UNAVAILABLE);
  EXPECT_EQ(echo.get<Echo>().remote_error->message, "call 'remote' refused");
  EXPECT_EQ(k.pending_calls(), 0u);
}

std::int64_t doubled(FakeKernel& k, std::int64_t v) {
  auto reply = k.call<DoubleRequest, DoubleReply>("double", double_request(v));
  return reply ? reply.value()->value() : -1;
}

TEST(FakeKernel, FirstActiveProviderAnswers) {
  FakeKernel k;
  auto a = active<Echo>(k, NodeOptions().with_name("a").with_params(R"({"factor": 2})"));
  auto b = active<Echo>(k, NodeOptions().with_name("b").with_params(R"({"factor": 5})"));
  EXPECT_EQ(doubled(k, 1), 2);
  ASSERT_TRUE(a.deactivate());
  EXPECT_EQ(doubled(k, 1), 5);
  EXPECT_EQ(b.state(), plr::NodeState::Active);
}

TEST(FakeKernel, FakeServiceAnswersANodeSynchronously) {
  FakeKernel k;
  k.fake_service<DoubleRequest, DoubleReply>(
      "remote", [](const DoubleRequest& req, flatbuffers::FlatBufferBuilder& reply) {
        reply.Finish(plr::msg::CreateDoubleReply(reply, req.value() * 10));
        return plr::Status{};
      });
  auto echo = active<Echo>(k);
  ASSERT_TRUE(k.publish<Count>("ask", count(4)));
  k.spin();
  EXPECT_EQ(echo.get<Echo>().remote_answer, 40);
  EXPECT_FALSE(echo.get<Echo>().remote_error.has_value());
  ASSERT_EQ(k.requests("remote").size(), 1u);
  EXPECT_EQ(k.requests("remote")[0].from, echo.name());
}

TEST(FakeKernel, FakeServiceScriptsAnError) {
  FakeKernel k;
  k.fake_service_error("remote", PLR_ERR_TIMEOUT, "planner busy");
  auto echo = active<Echo>(k);
  ASSERT_TRUE(k.publish<Count>("ask", count(4)));
  k.spin();
  ASSERT_TRUE(echo.get<Echo>().remote_error.has_value());
  EXPECT_EQ(echo.get<Echo>().remote_error->code, PLR_ERR_TIMEOUT);
  EXPECT_EQ(echo.get<Echo>().remote_error->message, "planner busy");
}

TEST(FakeKernel, TimeoutsFollowTheManualClock) {
  FakeKernel k;
  auto slow = active<Slow>(k);
  auto call = k.call_async<DoubleRequest, DoubleReply>("slow", double_request(1), 1s);
  k.spin();
  ASSERT_TRUE(slow.get<Slow>().held.has_value()) << "the request reached the node";
  EXPECT_EQ(slow.unanswered_requests(), 1u);
  k.advance(999ms);
  k.spin();
  EXPECT_FALSE(call.ready());
  k.advance(1ms);
  k.spin();
  ASSERT_TRUE(call.ready());
  EXPECT_EQ(call.result().error().code, PLR_ERR_TIMEOUT);
  EXPECT_EQ(call.result().error().message, "service 'slow': timed out");
  // A late answer is refused: every call completes exactly once.
  flatbuffers::FlatBufferBuilder late;
  late.Finish(plr::msg::CreateDoubleReply(late, 2));
  EXPECT_FALSE(slow.get<Slow>().held->reply(late));
  EXPECT_EQ(slow.unanswered_requests(), 0u);
}

TEST(FakeKernel, AsyncAnswerCompletesTheCall) {
  FakeKernel k;
  auto slow = active<Slow>(k);
  auto call = k.call_async<DoubleRequest, DoubleReply>("slow", double_request(1));
  k.spin();
  EXPECT_FALSE(call.ready());
  EXPECT_EQ(call.result().error().message, "call still pending");
  flatbuffers::FlatBufferBuilder answer;
  answer.Finish(plr::msg::CreateDoubleReply(answer, 99));
  ASSERT_TRUE(slow.get<Slow>().held->reply(answer));
  ASSERT_TRUE(call.ready());
  EXPECT_EQ(call.result().value()->value(), 99);
}

// As the kernel's node thread does: what the provider accepted while active
// reaches it before its deactivate hook, not after.
TEST(FakeKernel, ARequestAcceptedBeforeDeactivationIsDeliveredFirst) {
  FakeKernel k;
  auto slow = active<Slow>(k);
  auto call = k.call_async<DoubleRequest, DoubleReply>("slow", double_request(1));
  ASSERT_TRUE(slow.deactivate());
  EXPECT_TRUE(slow.get<Slow>().held.has_value());
  EXPECT_FALSE(call.ready());
  flatbuffers::FlatBufferBuilder answer;
  answer.Finish(plr::msg::CreateDoubleReply(answer, 5));
  ASSERT_TRUE(slow.get<Slow>().held->reply(answer));
  ASSERT_TRUE(call.ready());
  EXPECT_EQ(call.result().value()->value(), 5);
  // Once inactive it accepts nothing new.
  auto refused = k.call_async<DoubleRequest, DoubleReply>("slow", double_request(2));
  ASSERT_TRUE(refused.ready());
  EXPECT_EQ(refused.result().error().code, PLR_ERR_UNAVAILABLE);
}

TEST(FakeKernel, DestroyingAProviderAnswersItsHeldRequests) {
  FakeKernel k;
  auto slow = active<Slow>(k);
  auto call = k.call_async<DoubleRequest, DoubleReply>("slow", double_request(1));
  k.spin();
  slow.destroy();
  ASSERT_TRUE(call.ready());
  EXPECT_FALSE(call.result());
  EXPECT_EQ(k.pending_calls(), 0u);
}

TEST(FakeKernel, GarbageIsRejectedNotDelivered) {
  FakeKernel k;
  auto echo = active<Echo>(k);
  const std::uint8_t garbage[] = {0xff, 0xff, 0xff, 0x7f, 1, 2, 3, 4};
  ASSERT_TRUE(
      k.publish_raw("in", plr::MessageTraits<Count>::type_id(), 1, garbage, sizeof garbage));
  k.spin();
  EXPECT_TRUE(k.published("out").empty());
  ASSERT_EQ(k.rejections().size(), 1u);
  EXPECT_EQ(k.rejections()[0].node, echo.name());
  EXPECT_EQ(k.rejections()[0].reason, "message failed verification");
}

TEST(FakeKernel, TopicTypesMustAgree) {
  FakeKernel k;
  active<Echo>(k);
  EXPECT_EQ(k.subscribers("in"), 1u);
  auto s = k.publish<DoubleReply>("in", count(1));
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().code, PLR_ERR_INVALID);
  EXPECT_EQ(s.error().message, "publish 'in': type differs from the topic's");
}

TEST(FakeKernel, RemapsRenameTopicsAndServices) {
  FakeKernel k;
  auto echo = active<Echo>(
      k, NodeOptions().with_remap("in", "sensors/count").with_remap("double", "math/double"));
  EXPECT_EQ(echo.state(), plr::NodeState::Active);
  EXPECT_EQ(k.subscribers("sensors/count"), 1u);
  EXPECT_EQ(k.subscribers("in"), 0u);
  EXPECT_TRUE(k.has_provider("math/double"));
  ASSERT_TRUE(k.publish<Count>("sensors/count", count(1)));
  k.spin();
  EXPECT_EQ(k.published("out").size(), 1u);
}

TEST(FakeKernel, CountsLiveMessageBuffers) {
  FakeKernel k;
  auto echo = active<Echo>(k);
  ASSERT_TRUE(k.publish<Count>("in", count(1)));
  EXPECT_EQ(k.live_messages(), 1) << "queued for the subscriber";
  k.spin();
  EXPECT_EQ(k.live_messages(), 1) << "the node keeps the last message";
  {
    auto reply = k.call<DoubleRequest, DoubleReply>("double", double_request(2));
    ASSERT_TRUE(reply);
    EXPECT_EQ(k.live_messages(), 2) << "the test holds the reply";
  }
  EXPECT_EQ(k.live_messages(), 1);
  echo.destroy();
  EXPECT_EQ(k.live_messages(), 0);
}

TEST(FakeKernel, DuplicateNodeNamesAreRefused) {
  FakeKernel k;
  auto a = k.add<Echo>(NodeOptions().with_name("same"));
  EXPECT_EQ(a.name(), "same");
  EXPECT_THROW(k.add<Echo>(NodeOptions().with_name("same")), std::invalid_argument);
  EXPECT_THROW(k.add<Echo>(NodeOptions().with_name("other").with_params("[1]")),
               std::invalid_argument);
}

TEST(FakeKernel, LoadReportsTheFileAndTheCause) {
  FakeKernel k;
  auto missing = k.load("/nonexistent/demo.so");
  ASSERT_FALSE(missing);
  EXPECT_EQ(missing.error().message.rfind("/nonexistent/demo.so: dlopen failed: ", 0), 0u)
      << missing.error().message;
}

TEST(FakeKernel, LoadsAPluginByPath) {
  FakeKernel k;
  auto node = k.load_node(PLR_DEMO_DOUBLER, NodeOptions().with_params(R"({"factor": 3})"));
  ASSERT_TRUE(node) << node.error().message;
  EXPECT_EQ(node->name(), "demo_doubler");
  ASSERT_TRUE(node->configure());
  ASSERT_TRUE(node->activate());
  auto reply = k.call<DoubleRequest, DoubleReply>("double", double_request(5));
  ASSERT_TRUE(reply) << reply.error().message;
  EXPECT_EQ(reply.value()->value(), 15);
  ASSERT_TRUE(k.publish<Count>("count", count(1)));
  ASSERT_TRUE(k.publish<Count>("count", count(2)));
  k.spin();
  ASSERT_TRUE(node->deactivate());
  const auto logs = k.logs();
  ASSERT_FALSE(logs.empty());
  EXPECT_EQ(logs.back().node, "demo_doubler");
  EXPECT_EQ(logs.back().text, "saw 2 counts");
}

TEST(FakeKernel, CounterPluginCallsAFakeService) {
  FakeKernel k;
  k.fake_service<DoubleRequest, DoubleReply>(
      "double", [](const DoubleRequest& req, flatbuffers::FlatBufferBuilder& reply) {
        reply.Finish(plr::msg::CreateDoubleReply(reply, req.value() * 2));
        return plr::Status{};
      });
  auto node =
      k.load_node(PLR_DEMO_COUNTER, NodeOptions().with_params(R"({"period_ms": 0, "limit": 3})"));
  ASSERT_TRUE(node) << node.error().message;
  ASSERT_TRUE(node->configure());
  ASSERT_TRUE(node->activate());
  // The counter publishes from its own thread and stops after `limit`.
  ASSERT_TRUE(k.wait_published("doubled", 3, 10s));
  ASSERT_TRUE(node->deactivate());
  const auto doubled = k.published("doubled");
  ASSERT_EQ(doubled.size(), 3u);
  EXPECT_EQ(doubled[2].as<Count>()->value(), 4);
  EXPECT_EQ(k.requests("double").size(), 3u);
}

}  // namespace
