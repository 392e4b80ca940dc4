// Real processes (fork): messages cross address spaces, peers die by SIGKILL,
// and no segment of the run is left behind.
#include <gtest/gtest.h>

#include <cstring>

#include "test_util.hpp"

namespace plr::shm {
namespace {

using namespace std::chrono_literals;

constexpr char kTopic[] = "sim/box_poses";

class ProcessTest : public ::testing::Test {
 protected:
  Result<Publisher> make_pub(Policy p, std::uint32_t slots = 4, std::uint32_t size = 4096) {
    TopicConfig c;
    c.slot_count = slots;
    c.slot_size = size;
    c.policy = p;
    return PublisherBuilder().run_id(run_).topic(kTopic).config(c).create();
  }
  Result<Subscriber> make_sub() { return SubscriberBuilder().run_id(run_).topic(kTopic).create(); }
  static bool send(Publisher& p, std::uint32_t v, Timeout t = 5s) {
    auto l = p.loan(4096, t);
    if (!l) return false;
    for (std::size_t i = 0; i < 4096; i += 4) std::memcpy(l->data() + i, &v, 4);
    return p.publish(std::move(*l), MessageType{9, 1}, 0, 4096).has_value();
  }
  static bool check(const Sample& s, std::uint32_t v) {
    if (s.data().size() != 4096) return false;
    for (std::size_t i = 0; i < 4096; i += 4) {
      std::uint32_t x = 0;
      std::memcpy(&x, s.data().data() + i, 4);
      if (x != v) return false;
    }
    return true;
  }

  std::string run_ = test::unique_run_id();
};

TEST_F(ProcessTest, MessagesCrossProcessesReliably) {
  auto pub = make_pub(Policy::kReliable);
  ASSERT_TRUE(pub.has_value());
  test::Pipe ready;
  const pid_t child = test::fork_child([&] {
    auto sub = make_sub();
    if (!sub) return 10;
    ready.signal();
    for (std::uint32_t i = 0; i < 2000; ++i) {
      auto m = sub->take(5s);
      if (!m) return 11;
      if (m->info().seq != i || !check(*m, i * 7)) return 12;
    }
    return sub->counters().dropped_slow == 0 ? 0 : 13;
  });
  ASSERT_EQ(ready.wait(), 'x');
  for (std::uint32_t i = 0; i < 2000; ++i) ASSERT_TRUE(send(*pub, i * 7));
  EXPECT_EQ(test::wait_child(child), 0);
}

// A subscriber process takes two samples, holds them and is killed: the
// publisher's waiting loan reclaims its slots and table entry.
TEST_F(ProcessTest, KilledSubscriberHoldingSlotsIsReclaimed) {
  auto pub = make_pub(Policy::kReliable, 4);
  ASSERT_TRUE(pub.has_value());
  test::Pipe ready, holding;
  const pid_t child = test::fork_child([&] {
    auto sub = make_sub();
    if (!sub) return 10;
    ready.signal();
    auto a = sub->take(5s);
    auto b = sub->take(5s);
    if (!a || !b) return 11;
    holding.signal();
    ::pause();
    return 0;
  });
  ASSERT_EQ(ready.wait(), 'x');
  ASSERT_TRUE(send(*pub, 1));
  ASSERT_TRUE(send(*pub, 2));
  ASSERT_EQ(holding.wait(), 'x');
  ASSERT_TRUE(send(*pub, 3));
  ASSERT_TRUE(send(*pub, 4));
  EXPECT_EQ(pub->loan(16).error(), Error::kTimeout) << "ring full: two held, two unread";
  EXPECT_EQ(pub->subscriber_count(), 1u);

  ::kill(child, SIGKILL);
  // Not reaped yet: a zombie counts as dead. A slot, not kTimeout: the dead
  // reader's slots came back within the wait.
  auto l = pub->loan(16, 5s);
  EXPECT_TRUE(l.has_value()) << to_string(l.error());
  EXPECT_EQ(pub->subscriber_count(), 0u);
  l = pub->loan(16);  // replaces the first loan: its slot goes back
  EXPECT_EQ(test::wait_child(child), 128 + SIGKILL);
  // All four slots usable again.
  for (int i = 0; i < 8; ++i) ASSERT_TRUE(send(*pub, 100 + i, kNoWait));
}

// Keep-last never blocks, so nothing forces a reclaim there: a new subscriber
// that finds the table full frees the dead reader's entry and slots itself.
TEST_F(ProcessTest, NewSubscriberReclaimsDeadReaderOfFullTable) {
  TopicConfig c;
  c.slot_count = 2;
  c.slot_size = 4096;
  c.max_subscribers = 1;
  auto pub = PublisherBuilder().run_id(run_).topic(kTopic).config(c).create();
  ASSERT_TRUE(pub.has_value());
  ASSERT_TRUE(send(*pub, 1));
  test::Pipe ready, holding;
  const pid_t child = test::fork_child([&] {
    auto sub = make_sub();
    if (!sub) return 10;
    ready.signal();
    auto held = sub->take(5s);
    if (!held) return 11;
    holding.signal();
    ::pause();
    return 0;
  });
  ASSERT_EQ(ready.wait(), 'x');
  ASSERT_TRUE(send(*pub, 2));
  ASSERT_EQ(holding.wait(), 'x');
  EXPECT_EQ(make_sub().error(), Error::kTooManySubscribers);
  ::kill(child, SIGKILL);
  EXPECT_EQ(test::wait_child(child), 128 + SIGKILL);
  auto sub = make_sub();
  ASSERT_TRUE(sub.has_value()) << to_string(sub.error());
  // Both slots free again: two loans at once.
  auto l1 = pub->loan(16);
  auto l2 = pub->loan(16);
  EXPECT_TRUE(l1.has_value() && l2.has_value());
}

TEST_F(ProcessTest, SubscriberSeesPublisherDeath) {
  test::Pipe ready;
  const pid_t child = test::fork_child([&] {
    auto pub = make_pub(Policy::kKeepLast);
    if (!pub) return 10;
    send(*pub, 5);
    ready.signal();
    ::pause();
    return 0;
  });
  ASSERT_EQ(ready.wait(), 'x');
  auto sub = make_sub();
  ASSERT_TRUE(sub.has_value()) << to_string(sub.error());
  EXPECT_TRUE(sub->publisher_alive().has_value());
  ::kill(child, SIGKILL);
  EXPECT_EQ(test::wait_child(child), 128 + SIGKILL);
  // kPeerDead, not kTimeout: the death is noticed while the take waits.
  EXPECT_EQ(sub->take(10s).error(), Error::kPeerDead);
  // A restarted publisher replaces the dead one's segment.
  auto again = make_pub(Policy::kKeepLast);
  EXPECT_TRUE(again.has_value()) << to_string(again.error());
}

TEST_F(ProcessTest, SegmentsArePrivateAndGoneAfterCleanExit) {
  test::Pipe ready, done;
  const pid_t child = test::fork_child([&] {
    auto pub = make_pub(Policy::kKeepLast);
    auto srv = ServiceServerBuilder().run_id(run_).service("planner/plan").create();
    if (!pub || !srv) return 10;
    ready.signal();
    done.wait();
    return 0;  // destructors run: segments unlinked
  });
  ASSERT_EQ(ready.wait(), 'x');
  const auto names = test::run_segments(run_);
  ASSERT_EQ(names.size(), 2u);
  for (const auto& n : names) EXPECT_EQ(test::segment_mode("/" + n), 0600u) << n;
  done.signal();
  EXPECT_EQ(test::wait_child(child), 0);
  EXPECT_TRUE(test::run_segments(run_).empty());
}

TEST_F(ProcessTest, SegmentsOfKilledProcessAreReclaimed) {
  test::Pipe ready;
  const pid_t child = test::fork_child([&] {
    auto pub = make_pub(Policy::kReliable);
    auto srv = ServiceServerBuilder().run_id(run_).service("planner/plan").create();
    if (!pub || !srv) return 10;
    ready.signal();
    ::pause();
    return 0;
  });
  ASSERT_EQ(ready.wait(), 'x');
  // A live segment of another run must survive reclaim.
  auto live = make_pub(Policy::kKeepLast);
  ASSERT_FALSE(live.has_value());  // same topic: the child owns it
  EXPECT_EQ(live.error(), Error::kAlreadyExists);
  const std::string other_run = test::unique_run_id();
  auto other = PublisherBuilder().run_id(other_run).topic(kTopic).create();
  ASSERT_TRUE(other.has_value());

  ::kill(child, SIGKILL);
  EXPECT_EQ(test::wait_child(child), 128 + SIGKILL);
  // Reclaiming is machine-wide: a `plr run` starting beside this test
  // (ctest -j) may take some of the dead child's segments first. What
  // counts is that reclaiming leaves none of them, and the live one.
  const std::size_t left = test::run_segments(run_).size();
  EXPECT_LE(left, 2u);
  EXPECT_GE(reclaim_stale_segments(), left == 2 ? 2u : 0u);
  EXPECT_TRUE(test::run_segments(run_).empty());
  EXPECT_EQ(test::run_segments(other_run).size(), 1u) << "live owner's segment kept";
}

TEST_F(ProcessTest, RemoveRunSegmentsRemovesEverySegmentOfTheRun) {
  test::Pipe ready, done;
  const pid_t child = test::fork_child([&] {
    auto pub = make_pub(Policy::kKeepLast);
    if (!pub) return 10;
    ready.signal();
    done.wait();
    return 0;
  });
  ASSERT_EQ(ready.wait(), 'x');
  auto srv = ServiceServerBuilder().run_id(run_).service("executor/step").create();
  ASSERT_TRUE(srv.has_value());
  auto removed = remove_run_segments(run_);
  ASSERT_TRUE(removed.has_value());
  EXPECT_EQ(*removed, 2u);
  EXPECT_TRUE(test::run_segments(run_).empty());
  EXPECT_EQ(remove_run_segments("../etc").error(), Error::kInvalidArgument);
  done.signal();
  EXPECT_EQ(test::wait_child(child), 0);
}

TEST(ProcessStampTest, StartTimeDistinguishesReusedPids) {
  const ProcessStamp me = ProcessStamp::self();
  EXPECT_GT(me.start_time, 0u);
  EXPECT_TRUE(me.alive());
  EXPECT_FALSE((ProcessStamp{me.pid, me.start_time + 1}.alive()));
  const pid_t child = test::fork_child([] { return 0; });
  const ProcessStamp c = ProcessStamp::of(child);
  EXPECT_EQ(test::wait_child(child), 0);
  EXPECT_FALSE(c.alive());
}

}  // namespace
}  // namespace plr::shm
