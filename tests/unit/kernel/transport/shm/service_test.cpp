// Request/reply over shared memory: correlation, several clients, channel
// reuse, back-pressure, and a server that dies with requests pending.
#include <gtest/gtest.h>

#include <cstring>
#include <thread>

#include "test_util.hpp"

namespace plr::shm {
namespace {

using namespace std::chrono_literals;

constexpr MessageType kRequestType{100, 1};
constexpr MessageType kReplyType{101, 1};

class ServiceTest : public ::testing::Test {
 protected:
  ServiceServer make_server(std::uint32_t max_clients = 4, std::uint32_t slots = 4) {
    ServiceConfig c;
    c.max_clients = max_clients;
    c.slot_count = slots;
    c.slot_size = 256;
    auto s = ServiceServerBuilder().run_id(run_).service("planner/plan").config(c).create();
    EXPECT_TRUE(s.has_value()) << to_string(s.error());
    return std::move(*s);
  }
  Result<ServiceClient> make_client() {
    return ServiceClientBuilder().run_id(run_).service("planner/plan").create();
  }
  static std::uint64_t call(ServiceClient& c, std::uint32_t value) {
    auto l = c.loan_request(sizeof value);
    EXPECT_TRUE(l.has_value()) << to_string(l.error());
    std::memcpy(l->data(), &value, sizeof value);
    auto id = c.send_request(std::move(*l), kRequestType, 0, sizeof value);
    EXPECT_TRUE(id.has_value()) << to_string(id.error());
    return *id;
  }
  // Answers one request with value + 1000.
  static void serve_one(ServiceServer& s) {
    auto req = s.take_request(5s);
    ASSERT_TRUE(req.has_value()) << to_string(req.error());
    ASSERT_EQ(req->sample.info().type_id, kRequestType.type_id);
    std::uint32_t v = 0;
    std::memcpy(&v, req->sample.data().data(), sizeof v);
    v += 1000;
    auto l = s.loan_reply(req->reply_to, sizeof v, 5s);
    ASSERT_TRUE(l.has_value()) << to_string(l.error());
    std::memcpy(l->data(), &v, sizeof v);
    ASSERT_TRUE(s.send_reply(std::move(*l), req->reply_to, kReplyType, 0, sizeof v).has_value());
  }
  static std::uint32_t value(const Sample& s) {
    std::uint32_t v = 0;
    std::memcpy(&v, s.data().data(), sizeof v);
    return v;
  }

  std::string run_ = test::unique_run_id();
};

TEST_F(ServiceTest, ReplyEchoesCorrelationId) {
  ServiceServer server = make_server();
  auto client = make_client();
  ASSERT_TRUE(client.has_value());
  EXPECT_EQ(server.client_count(), 1u);
  const std::uint64_t id1 = call(*client, 1);
  const std::uint64_t id2 = call(*client, 2);
  EXPECT_NE(id1, id2);
  EXPECT_EQ(client->pending(), 2u);
  serve_one(server);
  serve_one(server);
  auto r1 = client->take_reply(1s);
  auto r2 = client->take_reply(1s);
  ASSERT_TRUE(r1.has_value() && r2.has_value());
  EXPECT_EQ(r1->info().correlation_id, id1);
  EXPECT_EQ(value(*r1), 1001u);
  EXPECT_EQ(r2->info().correlation_id, id2);
  EXPECT_EQ(value(*r2), 1002u);
  EXPECT_EQ(r2->info().type_id, kReplyType.type_id);
  EXPECT_EQ(client->pending(), 0u);
}

TEST_F(ServiceTest, RepliesGoToTheRightClient) {
  ServiceServer server = make_server();
  auto a = make_client();
  auto c = make_client();
  ASSERT_TRUE(a.has_value() && c.has_value());
  call(*a, 1);
  call(*c, 2);
  serve_one(server);
  serve_one(server);
  EXPECT_EQ(value(*a->take_reply(1s)), 1001u);
  EXPECT_EQ(value(*c->take_reply(1s)), 1002u);
  EXPECT_EQ(a->take_reply().error(), Error::kNoData);
}

TEST_F(ServiceTest, ClientTableIsBoundedAndChannelsAreReused) {
  ServiceServer server = make_server(1);
  {
    auto a = make_client();
    ASSERT_TRUE(a.has_value());
    EXPECT_EQ(make_client().error(), Error::kTooManyClients);
    call(*a, 1);
  }
  // The departed client's channel is freed by the server, stale request and all.
  EXPECT_EQ(server.reclaim_dead_clients(), 1u);
  auto b = make_client();
  ASSERT_TRUE(b.has_value()) << to_string(b.error());
  call(*b, 7);
  serve_one(server);
  auto r = b->take_reply(1s);
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(value(*r), 1007u);
}

TEST_F(ServiceTest, ReplyToDepartedClientIsRefused) {
  ServiceServer server = make_server();
  ReplyTo to;
  {
    auto a = make_client();
    ASSERT_TRUE(a.has_value());
    call(*a, 1);
    auto req = server.take_request(1s);
    ASSERT_TRUE(req.has_value());
    to = req->reply_to;
  }
  EXPECT_EQ(server.loan_reply(to, 4).error(), Error::kUnknownClient);
}

TEST_F(ServiceTest, RequestRingAppliesBackPressure) {
  ServiceServer server = make_server(1, 2);
  auto c = make_client();
  ASSERT_TRUE(c.has_value());
  call(*c, 1);
  call(*c, 2);
  EXPECT_EQ(c->loan_request(4, 10ms).error(), Error::kTimeout);
  serve_one(server);
  EXPECT_TRUE(c->loan_request(4, 1s).has_value());
}

TEST_F(ServiceTest, ServerThreadAnswersManyCalls) {
  ServiceServer server = make_server(2, 4);
  auto c = make_client();
  ASSERT_TRUE(c.has_value());
  constexpr std::uint32_t kCalls = 5000;
  std::thread t([&] {
    for (std::uint32_t i = 0; i < kCalls; ++i) serve_one(server);
  });
  for (std::uint32_t i = 0; i < kCalls; ++i) {
    const std::uint64_t id = call(*c, i);
    auto r = c->take_reply(5s);
    ASSERT_TRUE(r.has_value()) << to_string(r.error());
    ASSERT_EQ(r->info().correlation_id, id);
    ASSERT_EQ(value(*r), i + 1000);
  }
  t.join();
}

TEST_F(ServiceTest, CleanServerExitFailsPendingCall) {
  auto server = std::make_unique<ServiceServer>(make_server());
  auto c = make_client();
  ASSERT_TRUE(c.has_value());
  call(*c, 1);
  server.reset();
  EXPECT_EQ(c->take_reply(5s).error(), Error::kClosed);
  EXPECT_EQ(c->loan_request(4).error(), Error::kClosed);
}

// The server is a real process that dies (SIGKILL) holding our request: the
// waiting call fails with kPeerDead long before its 10 s timeout.
TEST_F(ServiceTest, PendingRequestToKilledServerFailsAtOnce) {
  test::Pipe ready, got;
  const pid_t pid = test::fork_child([&] {
    ServiceConfig cfg;
    auto s = ServiceServerBuilder().run_id(run_).service("planner/plan").config(cfg).create();
    if (!s) return 1;
    ready.signal();
    auto req = s->take_request(10s);
    if (!req) return 2;
    got.signal();
    ::raise(SIGKILL);
    return 3;
  });
  ASSERT_EQ(ready.wait(), 'x');
  auto c = make_client();
  ASSERT_TRUE(c.has_value()) << to_string(c.error());
  call(*c, 1);
  ASSERT_EQ(got.wait(), 'x');
  // kPeerDead, not kTimeout: the death is noticed while the client waits.
  auto r = c->take_reply(10s);
  ASSERT_FALSE(r.has_value());
  EXPECT_EQ(r.error(), Error::kPeerDead) << to_string(r.error());
  EXPECT_EQ(test::wait_child(pid), 128 + SIGKILL);
  // Later calls fail at once too.
  EXPECT_EQ(c->loan_request(4).error(), Error::kPeerDead);
  EXPECT_EQ(c->take_reply(10s).error(), Error::kPeerDead);
  // The dead server's segment is stale now.
  EXPECT_EQ(test::run_segments(run_).size(), 1u);
  EXPECT_GE(reclaim_stale_segments(), 1u);
  EXPECT_TRUE(test::run_segments(run_).empty());
}

}  // namespace
}  // namespace plr::shm
