// The in-process bus: zero-copy topics, overflow policies, services with
// exactly-once completion, timeouts, and counters.
#include "bus.hpp"
#include "kernel_fixture.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <future>
#include <latch>
#include <thread>

namespace plr::kernel {
namespace {

using namespace std::chrono_literals;

using testing::make_double_request;
using testing::make_msg;
using testing::TestEndpoint;

plr_msg* count_msg(std::int64_t v) {
  flatbuffers::FlatBufferBuilder fbb;
  fbb.Finish(msg::CreateCount(fbb, v));
  return make_msg<msg::Count>(fbb);
}

constexpr auto kCount = MessageTraits<msg::Count>::type_id();
constexpr auto kDoubleReq = MessageTraits<msg::DoubleRequest>::type_id();
constexpr auto kDoubleRep = MessageTraits<msg::DoubleReply>::type_id();

struct Received {
  std::mutex m;
  std::vector<std::int64_t> values;
  std::vector<const std::uint8_t*> data;
  static void on(void* user, const plr_msg* msg) {
    auto* self = static_cast<Received*>(user);
    const auto v = msg_view(msg);
    std::lock_guard lock(self->m);
    self->values.push_back(flatbuffers::GetRoot<msg::Count>(v.data)->value());
    self->data.push_back(v.data);
  }
  std::size_t size() {
    std::lock_guard lock(m);
    return values.size();
  }
};

TopicSettings topic_with(TopicPolicy policy, std::size_t depth) {
  TopicSettings t;
  t.policy = policy;
  t.depth = depth;
  return t;
}

class BusTest : public ::testing::Test {
 protected:
  void SetUp() override {
    baseline_ = live_messages();
    for (auto* e : {&a_, &b_, &c_}) bus_->set_live(e, true);
  }
  void TearDown() override {
    for (auto* e : {&a_, &b_, &c_}) {
      bus_->remove_endpoint(e);
      e->node_thread().drain();
    }
    bus_.reset();
    EXPECT_EQ(live_messages(), baseline_) << "message buffers leaked";
  }
  void settle() {
    for (auto* e : {&a_, &b_, &c_}) e->node_thread().drain();
  }

  std::int64_t baseline_ = 0;
  TestEndpoint a_{"a"}, b_{"b"}, c_{"c"};
  std::unique_ptr<Bus> bus_ = std::make_unique<Bus>();
};

TEST_F(BusTest, SubscribersShareThePublishersBuffer) {
  Received rb, rc;
  auto pub = bus_->advertise(&a_, "count", kCount, 1);
  ASSERT_TRUE(pub);
  ASSERT_TRUE(bus_->subscribe(&b_, "count", kCount, &Received::on, &rb));
  ASSERT_TRUE(bus_->subscribe(&c_, "count", kCount, &Received::on, &rc));
  plr_msg* m = count_msg(7);
  const auto* data = msg_view(m).data;
  ASSERT_TRUE(bus_->publish(*pub, m));
  settle();
  ASSERT_EQ(rb.values, std::vector<std::int64_t>{7});
  ASSERT_EQ(rc.values, std::vector<std::int64_t>{7});
  EXPECT_EQ(rb.data[0], data);
  EXPECT_EQ(rc.data[0], data);
  const auto stats = bus_->topic_stats();
  ASSERT_EQ(stats.size(), 1u);
  EXPECT_EQ(stats[0].messages, 1u);
  EXPECT_EQ(stats[0].subscribers, 2u);
}

TEST_F(BusTest, TopicRefusesASecondType) {
  ASSERT_TRUE(bus_->advertise(&a_, "count", kCount, 1));
  auto wrong = bus_->advertise(&b_, "count", kDoubleReq, 1);
  ASSERT_FALSE(wrong);
  EXPECT_NE(wrong.error().message.find("topic 'count' carries type"), std::string::npos)
      << wrong.error().message;
}

// "count" with `policy` and `depth`, published by a, read into `rb` by b,
// whose thread stays busy until `release` is set.
class SlowSubscriberTest : public BusTest {
 protected:
  void with(TopicPolicy policy, std::size_t depth) {
    bus_ = std::make_unique<Bus>([=](const std::string&) { return topic_with(policy, depth); });
    for (auto* e : {&a_, &b_, &c_}) bus_->set_live(e, true);
    pub = *bus_->advertise(&a_, "count", kCount, 1);
    ASSERT_TRUE(bus_->subscribe(&b_, "count", kCount, &Received::on, &rb));
    ASSERT_TRUE(b_.node_thread().post([gate = release.get_future().share()] { gate.wait(); }));
  }
  Received rb;
  std::uint64_t pub = 0;
  std::promise<void> release;
};

TEST_F(SlowSubscriberTest, KeepLastDropsTheOldest) {
  with(TopicPolicy::KeepLast, 4);
  for (int i = 0; i < 10; ++i) ASSERT_TRUE(bus_->publish(pub, count_msg(i)));
  release.set_value();
  settle();
  EXPECT_EQ(rb.values, (std::vector<std::int64_t>{6, 7, 8, 9}));
  EXPECT_EQ(bus_->topic_stats()[0].drops, 6u);
}

TEST_F(SlowSubscriberTest, ReliableMakesThePublisherWaitInsteadOfDropping) {
  with(TopicPolicy::Reliable, 2);
  std::thread opener([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    release.set_value();
  });
  for (int i = 0; i < 50; ++i) ASSERT_TRUE(bus_->publish(pub, count_msg(i)));
  opener.join();
  settle();
  EXPECT_EQ(rb.size(), 50u);
  EXPECT_EQ(bus_->topic_stats()[0].drops, 0u);
}

struct Replies {
  std::mutex m;
  std::condition_variable cv;
  std::map<std::uint64_t, int> count;
  std::vector<std::pair<plr_status, std::string>> results;
  std::vector<std::int64_t> values;
  static void on(void* user, plr_status status, const plr_msg* reply, const char* error) {
    auto* self = static_cast<Replies*>(user);
    std::lock_guard lock(self->m);
    self->results.emplace_back(status, error ? error : "");
    if (status == PLR_OK)
      self->values.push_back(flatbuffers::GetRoot<msg::DoubleReply>(msg_view(reply).data)->value());
    self->cv.notify_all();
  }
  void wait(std::size_t n) {
    std::unique_lock lock(m);
    cv.wait_for(lock, std::chrono::seconds(5), [&] { return results.size() >= n; });
  }
};

// Doubles synchronously, answering through the bus like a plug-in would.
struct Doubler {
  Bus* bus;
  static void on(void* user, const plr_msg* req, std::uint64_t token) {
    auto* self = static_cast<Doubler*>(user);
    const auto v = flatbuffers::GetRoot<msg::DoubleRequest>(msg_view(req).data)->value();
    flatbuffers::FlatBufferBuilder fbb;
    fbb.Finish(msg::CreateDoubleReply(fbb, 2 * v));
    (void)self->bus->respond(token, PLR_OK, make_msg<msg::DoubleReply>(fbb), "");
  }
};

TEST_F(BusTest, ServiceCallIsAnsweredOnce) {
  Doubler d{bus_.get()};
  ASSERT_TRUE(bus_->provide(&b_, "double", kDoubleReq, kDoubleRep, &Doubler::on, &d));
  Replies r;
  std::uint64_t id = 0;
  ASSERT_TRUE(bus_->call(&a_, "double", kDoubleReq, make_double_request(21),
                         std::chrono::seconds(1), &Replies::on, &r, &id));
  r.wait(1);
  ASSERT_EQ(r.results.size(), 1u);
  EXPECT_EQ(r.results[0].first, PLR_OK);
  EXPECT_EQ(r.values, std::vector<std::int64_t>{42});
  auto again = bus_->respond(id, PLR_OK, nullptr, "");
  ASSERT_FALSE(again);
  EXPECT_NE(again.error().message.find("already answered"), std::string::npos);
}

// Where a handler ran, and whether another of its node's callbacks was
// running at the time.
struct Where {
  explicit Where(Bus* b) : bus(b) {}
  Bus* bus;
  std::atomic<bool> inside{false};
  std::atomic<int> overlaps{0};
  std::mutex m;
  std::vector<std::thread::id> threads;
  static void on(void* user, const plr_msg* req, std::uint64_t token) {
    auto* self = static_cast<Where*>(user);
    if (self->inside.exchange(true)) ++self->overlaps;
    {
      std::lock_guard lock(self->m);
      self->threads.push_back(std::this_thread::get_id());
    }
    self->inside = false;
    Doubler d{self->bus};
    Doubler::on(&d, req, token);
  }
};

TEST_F(BusTest, AQuickServiceRunsOnTheCallersThreadWhenItsNodeIsIdle) {
  Where quick{bus_.get()}, normal{bus_.get()};
  ASSERT_TRUE(
      bus_->provide(&b_, "quick", kDoubleReq, kDoubleRep, &Where::on, &quick, PLR_SERVICE_QUICK));
  ASSERT_TRUE(bus_->provide(&c_, "normal", kDoubleReq, kDoubleRep, &Where::on, &normal));
  for (const char* service : {"quick", "normal"}) {
    Replies r;
    ASSERT_TRUE(bus_->call(&a_, service, kDoubleReq, make_double_request(21), 1s, &Replies::on, &r,
                           nullptr));
    r.wait(1);
    EXPECT_EQ(r.values, std::vector<std::int64_t>{42}) << service;
  }
  ASSERT_EQ(quick.threads.size(), 1u);
  ASSERT_EQ(normal.threads.size(), 1u);
  EXPECT_EQ(quick.threads[0], std::this_thread::get_id());
  EXPECT_NE(normal.threads[0], std::this_thread::get_id());
}

TEST_F(BusTest, AQuickServiceWaitsForItsNodesOtherCallbacks) {
  // The node is busy with a callback of its own: the quick request queues
  // behind it instead of running beside it.
  Where quick{bus_.get()};
  ASSERT_TRUE(
      bus_->provide(&b_, "quick", kDoubleReq, kDoubleRep, &Where::on, &quick, PLR_SERVICE_QUICK));
  std::promise<void> release;
  auto released = release.get_future().share();
  ASSERT_TRUE(b_.node_thread().post([&quick, released] {
    quick.inside = true;
    released.wait();
    quick.inside = false;
  }));
  Replies r;
  ASSERT_TRUE(
      bus_->call(&a_, "quick", kDoubleReq, make_double_request(1), 1s, &Replies::on, &r, nullptr));
  EXPECT_TRUE(r.results.empty());  // not run inline: the node is busy
  release.set_value();
  r.wait(1);
  EXPECT_EQ(quick.overlaps, 0);
  ASSERT_EQ(quick.threads.size(), 1u);
  EXPECT_NE(quick.threads[0], std::this_thread::get_id());

  // Many callers at once: one callback of the node at a time, all answered.
  constexpr int kCallers = 4, kCalls = 200;
  Replies all;
  std::vector<std::thread> callers;
  for (int t = 0; t < kCallers; ++t)
    callers.emplace_back([&] {
      for (int i = 0; i < kCalls; ++i)
        (void)bus_->call(&a_, "quick", kDoubleReq, make_double_request(i), 5s, &Replies::on, &all,
                         nullptr);
    });
  for (auto& t : callers) t.join();
  all.wait(kCallers * kCalls);
  EXPECT_EQ(all.results.size(), static_cast<std::size_t>(kCallers * kCalls));
  EXPECT_EQ(quick.overlaps, 0);
}

TEST_F(BusTest, UnknownServiceFlagsAreRefused) {
  Doubler d{bus_.get()};
  auto s = bus_->provide(&b_, "double", kDoubleReq, kDoubleRep, &Doubler::on, &d, 0x80);
  ASSERT_FALSE(s);
  EXPECT_NE(s.error().message.find("unknown flags"), std::string::npos);
}

TEST_F(BusTest, CallWithoutProviderFailsAtOnce) {
  Replies r;
  auto s = bus_->call(&a_, "nobody", kDoubleReq, make_double_request(1), std::chrono::seconds(1),
                      &Replies::on, &r, nullptr);
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().code, PLR_ERR_UNAVAILABLE);
  EXPECT_EQ(s.error().message, "no provider for service 'nobody'");
  EXPECT_TRUE(r.results.empty());
}

struct Silent {
  std::vector<std::uint64_t> tokens;
  std::mutex m;
  static void on(void* user, const plr_msg*, std::uint64_t token) {
    auto* self = static_cast<Silent*>(user);
    std::lock_guard lock(self->m);
    self->tokens.push_back(token);
  }
};

TEST_F(BusTest, UnansweredCallTimesOutAndALateAnswerIsRefused) {
  Silent s;
  ASSERT_TRUE(bus_->provide(&b_, "slow", kDoubleReq, kDoubleRep, &Silent::on, &s));
  Replies r;
  ASSERT_TRUE(bus_->call(&a_, "slow", kDoubleReq, make_double_request(1),
                         std::chrono::milliseconds(30), &Replies::on, &r, nullptr));
  r.wait(1);
  ASSERT_EQ(r.results.size(), 1u);
  EXPECT_EQ(r.results[0].first, PLR_ERR_TIMEOUT);
  EXPECT_EQ(r.results[0].second, "call to 'slow' timed out after 30 ms");
  settle();
  ASSERT_EQ(s.tokens.size(), 1u);
  EXPECT_FALSE(bus_->respond(s.tokens[0], PLR_OK, make_double_request(0), ""));
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  EXPECT_EQ(r.results.size(), 1u);
}

// The timer thread sleeps until the deadline it last chose, also after that
// call has completed, and is woken only for an earlier one: every call must
// still time out, never before its deadline. (Replies::wait gives up after
// 5 s: a timer that is not woken leaves the call without a result.) "Not
// before" is shown by an event, not a clock: a call answered while an
// earlier deadline fires gets its answer.
TEST_F(BusTest, CallsTimeOutWhateverTheTimerThreadSleepsUntil) {
  Silent s;
  ASSERT_TRUE(bus_->provide(&b_, "slow", kDoubleReq, kDoubleRep, &Silent::on, &s));
  const auto cancelled_call = [&](std::chrono::milliseconds timeout) {
    Replies r;
    std::uint64_t id = 0;
    ASSERT_TRUE(bus_->call(&a_, "slow", kDoubleReq, make_double_request(1), timeout, &Replies::on,
                           &r, &id));
    ASSERT_TRUE(bus_->cancel(id));
    r.wait(1);
  };
  const auto time_out = [&](std::chrono::milliseconds timeout) {
    Replies r;
    EXPECT_TRUE(bus_->call(&a_, "slow", kDoubleReq, make_double_request(1), timeout, &Replies::on,
                           &r, nullptr));
    r.wait(1);
    ASSERT_EQ(r.results.size(), 1u) << "never timed out";
    EXPECT_EQ(r.results[0].first, PLR_ERR_TIMEOUT);
  };
  const auto answered_while_an_earlier_deadline_fires = [&] {
    Replies r;
    EXPECT_TRUE(bus_->call(&a_, "slow", kDoubleReq, make_double_request(1), 30s, &Replies::on, &r,
                           nullptr));
    Replies earlier;
    EXPECT_TRUE(bus_->call(&a_, "slow", kDoubleReq, make_double_request(1), 10ms, &Replies::on,
                           &earlier, nullptr));
    earlier.wait(1);
    ASSERT_EQ(earlier.results.size(), 1u) << "the earlier call never timed out";
    settle();
    std::uint64_t token = 0;
    {
      std::lock_guard lock(s.m);
      ASSERT_GE(s.tokens.size(), 2u);
      token = s.tokens[s.tokens.size() - 2];
    }
    EXPECT_TRUE(bus_->respond(token, PLR_OK, make_double_request(2), "")) << "timed out early";
    r.wait(1);
    ASSERT_EQ(r.results.size(), 1u);
    EXPECT_EQ(r.results[0].first, PLR_OK);
  };
  // The timer sleeps until the first call's deadline; the second one's comes later.
  cancelled_call(100ms);
  time_out(300ms);
  // The timer sleeps for 30 s; the next deadline comes first and must wake it.
  cancelled_call(30s);
  time_out(50ms);
  answered_while_an_earlier_deadline_fires();
  settle();
}

TEST_F(BusTest, CancelCompletesTheCallOnce) {
  Silent s;
  ASSERT_TRUE(bus_->provide(&b_, "slow", kDoubleReq, kDoubleRep, &Silent::on, &s));
  Replies r;
  std::uint64_t id = 0;
  ASSERT_TRUE(bus_->call(&a_, "slow", kDoubleReq, make_double_request(1), std::chrono::seconds(5),
                         &Replies::on, &r, &id));
  ASSERT_TRUE(bus_->cancel(id));
  ASSERT_TRUE(bus_->cancel(id));
  r.wait(1);
  settle();  // the provider still sees the request; `s` must outlive that
  ASSERT_EQ(r.results.size(), 1u);
  EXPECT_EQ(r.results[0].first, PLR_ERR_CANCELLED);
}

TEST_F(BusTest, ProviderGoingAwayFailsItsPendingCalls) {
  Silent s;
  ASSERT_TRUE(bus_->provide(&b_, "slow", kDoubleReq, kDoubleRep, &Silent::on, &s));
  Replies r;
  for (int i = 0; i < 3; ++i)
    ASSERT_TRUE(bus_->call(&a_, "slow", kDoubleReq, make_double_request(i), std::chrono::seconds(5),
                           &Replies::on, &r, nullptr));
  settle();
  bus_->remove_endpoint(&b_);
  r.wait(3);
  ASSERT_EQ(r.results.size(), 3u);
  for (const auto& [status, error] : r.results) {
    EXPECT_EQ(status, PLR_ERR_UNAVAILABLE);
    EXPECT_EQ(error, "provider 'b' of 'slow' went away before answering");
  }
}

// A reply already taken off the pending table runs the caller's callback
// unlocked (here on the provider's thread, as the shared-memory bridge's
// reply thread does). Removing the caller meanwhile must wait for it: the
// caller's code and memory go right after.
struct SlowReply {
  std::atomic<bool> entered{false}, done{false};
  static void on(void* user, plr_status, const plr_msg*, const char*) {
    auto* self = static_cast<SlowReply*>(user);
    self->entered = true;
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    self->done = true;
  }
};

TEST_F(BusTest, RemovingACallerWaitsForItsReplyCallbackToReturn) {
  Silent s;
  ASSERT_TRUE(bus_->provide(&b_, "slow", kDoubleReq, kDoubleRep, &Silent::on, &s));
  SlowReply r;
  ASSERT_TRUE(bus_->call(&a_, "slow", kDoubleReq, make_double_request(1), std::chrono::seconds(5),
                         &SlowReply::on, &r, nullptr));
  settle();
  ASSERT_EQ(s.tokens.size(), 1u);
  std::thread replier(
      [&] { EXPECT_TRUE(bus_->respond(s.tokens[0], PLR_OK, make_double_request(2), "")); });
  while (!r.entered) std::this_thread::yield();
  bus_->remove_endpoint(&a_);
  EXPECT_TRUE(r.done);
  replier.join();
}

// What an endpoint registered goes with it: an unconfigured node publishes nothing.
TEST_F(BusTest, ARemovedEndpointsPublishersAreGone) {
  auto pub = bus_->advertise(&a_, "count", kCount, 1);
  ASSERT_TRUE(pub);
  bus_->remove_endpoint(&a_);
  const Status s = bus_->publish(*pub, count_msg(1));
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().code, PLR_ERR_INVALID);
  std::uint8_t* data = nullptr;
  EXPECT_EQ(bus_->loan(*pub, 16, &data), nullptr);
}

TEST_F(BusTest, NonLiveEndpointsGetNothing) {
  Received rb;
  auto pub = bus_->advertise(&a_, "count", kCount, 1);
  ASSERT_TRUE(bus_->subscribe(&b_, "count", kCount, &Received::on, &rb));
  bus_->set_live(&b_, false);
  ASSERT_TRUE(bus_->publish(*pub, count_msg(1)));
  settle();
  EXPECT_EQ(rb.size(), 0u);
}

}  // namespace
}  // namespace plr::kernel
