// In-process semantics of the topic ring: loan/publish/take, several readers,
// keep-last and reliable policies, slot return, corrupt input, threads.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/mman.h>

#include <atomic>
#include <cstring>
#include <random>
#include <thread>

#include "layout.hpp"
#include "ring.hpp"
#include "test_util.hpp"

namespace plr::shm {
namespace {

using namespace std::chrono_literals;
using test::b;

TopicConfig config(std::uint32_t slots, std::uint32_t size, Policy p,
                   WaitMode w = WaitMode::kBlocking) {
  TopicConfig c;
  c.slot_count = slots;
  c.slot_size = size;
  c.max_subscribers = 8;
  c.policy = p;
  c.wait_mode = w;
  return c;
}

class TopicTest : public ::testing::Test {
 protected:
  Publisher make_pub(const TopicConfig& c) {
    auto p = PublisherBuilder().run_id(run_).topic("telemetry/joint_state").config(c).create();
    EXPECT_TRUE(p.has_value()) << to_string(p.error());
    return std::move(*p);
  }
  Subscriber make_sub() {
    auto s = SubscriberBuilder().run_id(run_).topic("telemetry/joint_state").create();
    EXPECT_TRUE(s.has_value()) << to_string(s.error());
    return std::move(*s);
  }
  // Publishes one message whose payload is `value` repeated `size` times.
  static std::uint64_t send(Publisher& p, int value, std::size_t size = 8) {
    auto l = p.loan(size);
    EXPECT_TRUE(l.has_value()) << to_string(l.error());
    std::memset(l->data(), value, size);
    auto seq = p.publish(std::move(*l), MessageType{42, 3}, 0, size);
    EXPECT_TRUE(seq.has_value());
    return *seq;
  }
  static int first_byte(const Sample& s) { return std::to_integer<int>(s.data()[0]); }

  // A publisher's segment mapped as a foreign process would map it.
  struct Mapping {
    explicit Mapping(const Publisher& pub) {
      const int fd = ::shm_open(pub.segment_name().c_str(), O_RDWR, 0);
      struct stat st {};
      if (fd < 0 || ::fstat(fd, &st) != 0) return;
      size = static_cast<std::size_t>(st.st_size);
      void* p = ::mmap(nullptr, size, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
      ::close(fd);
      if (p != MAP_FAILED) base = static_cast<std::byte*>(p);
    }
    ~Mapping() {
      if (base != nullptr) ::munmap(base, size);
    }
    std::byte* base = nullptr;
    std::size_t size = 0;
  };

  std::string run_ = test::unique_run_id();
};

TEST_F(TopicTest, LoanPublishTakeReadsInPlaceWithHeader) {
  Publisher pub = make_pub(config(4, 256, Policy::kKeepLast));
  Subscriber sub = make_sub();
  auto loan = pub.loan(200);
  ASSERT_TRUE(loan.has_value());
  EXPECT_EQ(loan->capacity(), 256u);
  // FlatBuffers builds at the end of its buffer: publish the tail.
  const std::size_t size = 40, offset = loan->capacity() - size;
  for (std::size_t i = 0; i < size; ++i) loan->data()[offset + i] = b(static_cast<int>(i));
  std::byte* slot_bytes = loan->data() + offset;
  auto seq = pub.publish(std::move(*loan), MessageType{0xfeedULL, 7}, offset, size);
  ASSERT_TRUE(seq.has_value());
  EXPECT_EQ(*seq, 0u);

  auto s = sub.take();
  ASSERT_TRUE(s.has_value()) << to_string(s.error());
  EXPECT_EQ(s->info().type_id, 0xfeedULL);
  EXPECT_EQ(s->info().schema_version, 7u);
  EXPECT_EQ(s->info().size, size);
  EXPECT_EQ(s->info().seq, 0u);
  ASSERT_EQ(s->data().size(), size);
  EXPECT_EQ(s->data()[39], b(39));
  // In place, not a copy: a write through the publisher's mapping shows up.
  slot_bytes[39] = b(0x55);
  EXPECT_EQ(s->data()[39], b(0x55));
  EXPECT_EQ(sub.take().error(), Error::kNoData);
  EXPECT_EQ(sub.counters().received, 1u);
  EXPECT_EQ(pub.counters().published, 1u);
}

TEST_F(TopicTest, SeveralSubscribersEachGetEveryMessage) {
  Publisher pub = make_pub(config(8, 64, Policy::kReliable));
  Subscriber a = make_sub(), b2 = make_sub(), c = make_sub();
  EXPECT_EQ(pub.subscriber_count(), 3u);
  for (int i = 0; i < 5; ++i) send(pub, i);
  for (Subscriber* s : {&a, &b2, &c}) {
    for (int i = 0; i < 5; ++i) {
      auto m = s->take();
      ASSERT_TRUE(m.has_value());
      EXPECT_EQ(m->info().seq, static_cast<std::uint64_t>(i));
      EXPECT_EQ(first_byte(*m), i);
    }
    EXPECT_EQ(s->take().error(), Error::kNoData);
  }
}

TEST_F(TopicTest, KeepLastDropsOldestAndCountsIt) {
  Publisher pub = make_pub(config(4, 64, Policy::kKeepLast));
  Subscriber sub = make_sub();
  for (int i = 0; i < 10; ++i) send(pub, i);  // never blocks
  for (int i = 6; i < 10; ++i) {
    auto m = sub.take();
    ASSERT_TRUE(m.has_value());
    EXPECT_EQ(m->info().seq, static_cast<std::uint64_t>(i));
    EXPECT_EQ(first_byte(*m), i);
  }
  EXPECT_EQ(sub.take().error(), Error::kNoData);
  EXPECT_EQ(sub.counters().dropped_slow, 6u);
  EXPECT_EQ(sub.counters().received, 4u);
}

TEST_F(TopicTest, KeepLastNeverOverwritesAHeldSample) {
  Publisher pub = make_pub(config(4, 64, Policy::kKeepLast));
  Subscriber sub = make_sub();
  send(pub, 7);
  auto held = sub.take();
  ASSERT_TRUE(held.has_value());
  for (int i = 0; i < 20; ++i) send(pub, 100 + i);
  for (std::byte x : held->data()) EXPECT_EQ(x, b(7));
  // Only three slots rotate while one is held: the newest three (18..20) survive.
  auto m = sub.take();
  ASSERT_TRUE(m.has_value());
  EXPECT_EQ(m->info().seq, 18u);
  EXPECT_EQ(first_byte(*m), 117);  // seq k carries 100 + k - 1
}

TEST_F(TopicTest, KeepLastFailsOnlyWhenReadersHoldEverySlot) {
  Publisher pub = make_pub(config(2, 64, Policy::kKeepLast));
  Subscriber sub = make_sub();
  send(pub, 1);
  send(pub, 2);
  auto s1 = sub.take();
  auto s2 = sub.take();
  ASSERT_TRUE(s1 && s2);
  EXPECT_EQ(pub.loan(8).error(), Error::kSlotsExhausted);
  { Sample drop = std::move(*s1); }
  EXPECT_TRUE(pub.loan(8).has_value());
}

TEST_F(TopicTest, ReliableAppliesBackPressureUntilReaderMovesOn) {
  Publisher pub = make_pub(config(4, 64, Policy::kReliable));
  Subscriber sub = make_sub();
  for (int i = 0; i < 4; ++i) send(pub, i);
  EXPECT_EQ(pub.loan(8).error(), Error::kTimeout);
  EXPECT_EQ(pub.loan(8, 30ms).error(), Error::kTimeout);
  {
    auto m = sub.take();
    ASSERT_TRUE(m.has_value());
    EXPECT_EQ(m->info().seq, 0u);
    EXPECT_EQ(pub.loan(8).error(), Error::kTimeout) << "slot still held by the reader";
  }
  send(pub, 4);
  for (int i = 1; i < 5; ++i) {
    auto m = sub.take();
    ASSERT_TRUE(m.has_value());
    EXPECT_EQ(first_byte(*m), i);
  }
  EXPECT_EQ(sub.counters().dropped_slow, 0u);
}

TEST_F(TopicTest, SlotReturnsOnlyWhenEveryReaderIsDone) {
  Publisher pub = make_pub(config(1, 64, Policy::kReliable));
  Subscriber a = make_sub(), c = make_sub();
  send(pub, 1);
  {
    auto m = a.take();
    ASSERT_TRUE(m.has_value());
  }
  EXPECT_EQ(pub.loan(8).error(), Error::kTimeout) << "c has not read it yet";
  {
    auto held = c.take();
    ASSERT_TRUE(held.has_value());
    EXPECT_EQ(pub.loan(8).error(), Error::kTimeout) << "c still holds it";
  }
  EXPECT_TRUE(pub.loan(8).has_value());
}

TEST_F(TopicTest, ReliableWaitingPublisherWakesWhenReaderReleases) {
  Publisher pub = make_pub(config(2, 64, Policy::kReliable));
  Subscriber sub = make_sub();
  send(pub, 0);
  send(pub, 1);
  std::thread reader([&] {
    for (int i = 0; i < 3; ++i) {
      auto m = sub.take(5s);
      ASSERT_TRUE(m.has_value());
      EXPECT_EQ(first_byte(*m), i);
    }
  });
  auto l = pub.loan(8, 5s);
  ASSERT_TRUE(l.has_value()) << to_string(l.error());
  std::memset(l->data(), 2, 8);
  ASSERT_TRUE(pub.publish(std::move(*l), MessageType{42, 3}, 0, 8).has_value());
  reader.join();
}

TEST_F(TopicTest, SizeLimitsAreChecked) {
  Publisher pub = make_pub(config(2, 64, Policy::kKeepLast));
  EXPECT_EQ(pub.loan(65).error(), Error::kTooLarge);
  auto l = pub.loan(64);
  ASSERT_TRUE(l.has_value());
  EXPECT_EQ(pub.publish(std::move(*l), MessageType{}, 60, 5).error(), Error::kInvalidArgument);
  // The failed publish gave the slot back: both slots loanable again.
  auto l1 = pub.loan(8);
  auto l2 = pub.loan(8);
  EXPECT_TRUE(l1.has_value() && l2.has_value());
}

TEST_F(TopicTest, UnpublishedLoanReturnsItsSlot) {
  Publisher pub = make_pub(config(1, 64, Policy::kKeepLast));
  { auto l = pub.loan(8); }
  EXPECT_TRUE(pub.loan(8).has_value());
}

TEST_F(TopicTest, BadConfigAndNamesAreRefused) {
  EXPECT_EQ(PublisherBuilder().run_id("bad/run").topic("x").create().error(),
            Error::kInvalidArgument);
  EXPECT_EQ(PublisherBuilder().run_id(run_).topic("").create().error(), Error::kInvalidArgument);
  TopicConfig c;
  c.slot_count = 0;
  EXPECT_EQ(PublisherBuilder().run_id(run_).topic("x").config(c).create().error(),
            Error::kInvalidArgument);
  c = TopicConfig{};
  c.max_subscribers = 64;
  EXPECT_EQ(PublisherBuilder().run_id(run_).topic("x").config(c).create().error(),
            Error::kInvalidArgument);
  EXPECT_EQ(SubscriberBuilder().run_id(run_).topic("nobody").create().error(), Error::kNotFound);
}

TEST_F(TopicTest, OnePublisherPerTopicAndSubscriberTableIsBounded) {
  TopicConfig c = config(2, 64, Policy::kKeepLast);
  c.max_subscribers = 2;
  Publisher pub = make_pub(c);
  EXPECT_EQ(PublisherBuilder().run_id(run_).topic("telemetry/joint_state").create().error(),
            Error::kAlreadyExists);
  Subscriber a = make_sub(), c2 = make_sub();
  EXPECT_EQ(SubscriberBuilder().run_id(run_).topic("telemetry/joint_state").create().error(),
            Error::kTooManySubscribers);
}

TEST_F(TopicTest, SegmentIsPrivateAndRemovedWithItsPublisher) {
  std::string name;
  {
    Publisher pub = make_pub(config(2, 64, Policy::kKeepLast));
    name = pub.segment_name();
    EXPECT_EQ(test::segment_mode(name), 0600u);
    EXPECT_EQ(test::run_segments(run_).size(), 1u);
  }
  EXPECT_TRUE(test::run_segments(run_).empty());
}

TEST_F(TopicTest, SubscriberSeesCleanCloseAfterDraining) {
  auto pub = std::make_unique<Publisher>(make_pub(config(4, 64, Policy::kKeepLast)));
  Subscriber sub = make_sub();
  send(*pub, 5);
  pub.reset();
  auto m = sub.take(1s);
  ASSERT_TRUE(m.has_value());
  EXPECT_EQ(first_byte(*m), 5);
  EXPECT_EQ(sub.take(1s).error(), Error::kClosed);
  EXPECT_EQ(sub.publisher_alive().error(), Error::kClosed);
}

TEST_F(TopicTest, TakeTimesOut) {
  Publisher pub = make_pub(config(2, 64, Policy::kKeepLast));
  Subscriber sub = make_sub();
  EXPECT_EQ(sub.take(20ms).error(), Error::kTimeout);
  EXPECT_TRUE(sub.publisher_alive().has_value());
}

// A waiting take returns the sample published while it waits, not a timeout.
TEST_F(TopicTest, TakeWaitsForTheNextSample) {
  Publisher pub = make_pub(config(2, 64, Policy::kKeepLast));
  Subscriber sub = make_sub();
  std::atomic<bool> published{false};
  std::thread publisher([&] {
    std::this_thread::sleep_for(20ms);
    published = true;
    send(pub, 7);
  });
  auto m = sub.take(30s);
  const bool after_publish = published;
  publisher.join();
  ASSERT_TRUE(m.has_value());
  EXPECT_TRUE(after_publish);
  EXPECT_EQ(first_byte(*m), 7);
}

// A loan blocked by a reliable reader goes on once the reader lets a slot go.
TEST_F(TopicTest, ReliableLoanWaitsForTheReaderToLetGo) {
  Publisher pub = make_pub(config(2, 64, Policy::kReliable));
  Subscriber sub = make_sub();
  for (int i = 0; i < 2; ++i) send(pub, i);
  std::atomic<bool> released{false};
  std::thread reader([&] {
    std::this_thread::sleep_for(20ms);
    released = true;
    auto m = sub.take();
    ASSERT_TRUE(m.has_value());
  });
  auto slot = pub.loan(8, 30s);
  const bool after_release = released;
  reader.join();
  ASSERT_TRUE(slot.has_value());
  EXPECT_TRUE(after_release);
}

// Writes garbage where another process could: the reader drops and counts it.
TEST_F(TopicTest, CorruptHeaderIsDroppedAndCounted) {
  Publisher pub = make_pub(config(8, 64, Policy::kKeepLast));
  Subscriber sub = make_sub();
  for (int i = 0; i < 4; ++i) send(pub, i);

  const Mapping segment(pub);
  ASSERT_NE(segment.base, nullptr);
  auto* base = segment.base + detail::align_up(sizeof(detail::SegmentHeader), 64);
  const detail::Ring ring =
      detail::Ring::view(base, reinterpret_cast<detail::RingHeader*>(base)->geo, nullptr);
  // Message 1: size beyond the slot. Message 2: descriptor names slot 9999.
  const auto d1 = ring.desc[1].load();
  ring.slot(detail::desc_slot(d1)).size = 0xffffffffu;
  ring.desc[2].store(detail::pack_desc(2, 9999));

  auto m = sub.take();
  ASSERT_TRUE(m.has_value());
  EXPECT_EQ(m->info().seq, 0u);
  m = sub.take();
  ASSERT_TRUE(m.has_value()) << to_string(m.error());
  EXPECT_EQ(m->info().seq, 3u);
  EXPECT_EQ(first_byte(*m), 3);
  EXPECT_EQ(sub.counters().dropped_invalid, 2u);
  EXPECT_EQ(sub.counters().received, 2u);

  // A scribbled head far ahead is skipped in one step, not looped over.
  ring.header->head.store(1ULL << 40);
  EXPECT_EQ(sub.take().error(), Error::kNoData);
  EXPECT_GE(sub.counters().dropped_invalid, 3u);

  // A bad magic makes the segment unusable for new subscribers.
  reinterpret_cast<detail::SegmentHeader*>(segment.base)->layout_version = 99;
  EXPECT_EQ(SubscriberBuilder().run_id(run_).topic("telemetry/joint_state").create().error(),
            Error::kIncompatible);
}

// Seeded random scribbles over the whole ring (headers, descriptors, reader
// table, slots) between publishes: the reader never crashes, never loops
// forever, and every sample it returns lies inside a slot.
TEST_F(TopicTest, RandomScribblesNeverBreakTheReader) {
  const TopicConfig cfg = config(8, 128, Policy::kKeepLast);
  Publisher pub = make_pub(cfg);
  Subscriber sub = make_sub();
  const Mapping segment(pub);
  ASSERT_NE(segment.base, nullptr);
  const std::size_t ring_off = detail::align_up(sizeof(detail::SegmentHeader), 64);
  auto* bytes = reinterpret_cast<std::uint8_t*>(segment.base);
  std::mt19937_64 rng(12345);
  std::uint64_t returned = 0;
  for (int round = 0; round < 2000; ++round) {
    for (int i = 0; i < 3; ++i) {
      if (auto l = pub.loan(16)) {
        std::memset(l->data(), round & 0xff, 16);
        (void)pub.publish(std::move(*l), MessageType{1, 1}, 0, 16);
      }
    }
    for (int k = 0; k < 4; ++k) {
      const std::size_t at = ring_off + rng() % (segment.size - ring_off);
      bytes[at] = static_cast<std::uint8_t>(rng());
    }
    for (int t = 0; t < 8; ++t) {
      auto m = sub.take();
      if (!m) break;
      ++returned;
      ASSERT_LE(m->data().size(), cfg.slot_size);
    }
  }
  const Counters c = sub.counters();
  EXPECT_GT(returned, 0u);
  EXPECT_GT(c.dropped_invalid, 0u);
}

class TopicThreadsTest : public TopicTest, public ::testing::WithParamInterface<WaitMode> {};

TEST_P(TopicThreadsTest, ReliableStreamBetweenThreadsLosesNothing) {
  constexpr int kCount = 20000;
  Publisher pub = make_pub(config(8, 64, Policy::kReliable, GetParam()));
  Subscriber s1 = make_sub(), s2 = make_sub();
  auto reader = [](Subscriber& s) {
    for (std::uint64_t i = 0; i < kCount; ++i) {
      auto m = s.take(10s);
      ASSERT_TRUE(m.has_value()) << to_string(m.error());
      ASSERT_EQ(m->info().seq, i);
      std::uint64_t v = 0;
      std::memcpy(&v, m->data().data(), sizeof v);
      ASSERT_EQ(v, i * 3);
    }
  };
  std::thread t1(reader, std::ref(s1)), t2(reader, std::ref(s2));
  for (std::uint64_t i = 0; i < kCount; ++i) {
    auto l = pub.loan(8, 10s);
    ASSERT_TRUE(l.has_value()) << to_string(l.error());
    const std::uint64_t v = i * 3;
    std::memcpy(l->data(), &v, sizeof v);
    ASSERT_TRUE(pub.publish(std::move(*l), MessageType{1, 1}, 0, 8).has_value());
  }
  t1.join();
  t2.join();
  EXPECT_EQ(s1.counters().dropped_slow + s2.counters().dropped_slow, 0u);
}

INSTANTIATE_TEST_SUITE_P(Modes, TopicThreadsTest,
                         ::testing::Values(WaitMode::kBlocking, WaitMode::kPolling),
                         [](const auto& info) {
                           return info.param == WaitMode::kBlocking ? "Blocking" : "Polling";
                         });

TEST_F(TopicTest, PublishSharedKeepsTheSlotForLocalReadersOfTheSameBytes) {
  Publisher pub = make_pub(config(2, 64, Policy::kKeepLast));
  Subscriber sub = make_sub();
  auto l = pub.loan(8);
  ASSERT_TRUE(l.has_value());
  std::byte* slot = l->data();
  std::memset(slot, 7, 8);
  auto local = pub.publish_shared(std::move(*l), MessageType{42, 3}, 2, 4);
  ASSERT_TRUE(local.has_value()) << to_string(local.error());
  EXPECT_EQ(local->data().data(), slot + 2) << "the publisher's process reads the slot in place";
  EXPECT_EQ(local->info().seq, 0u);
  auto remote = sub.take();
  ASSERT_TRUE(remote.has_value());
  EXPECT_EQ(remote->info().seq, 0u);  // its own mapping of the same slot
  EXPECT_EQ(remote->info().size, 4u);
  EXPECT_EQ(std::to_integer<int>(remote->data()[3]), 7);
  remote = sub.take(kNoWait);  // drops the subscriber's hold (kNoData)
  // Keep-last may overwrite any slot nobody holds: only the other one is free.
  for (int i = 0; i < 3; ++i) {
    auto again = pub.loan(8);
    ASSERT_TRUE(again.has_value());
    EXPECT_NE(again->data(), slot) << "a slot held by the publisher's process is not reused";
  }
  local = Error::kNoData;  // drops the hold
  bool reused = false;
  for (int i = 0; i < 2 && !reused; ++i) {
    auto again = pub.loan(8);
    ASSERT_TRUE(again.has_value());
    reused = again->data() == slot;
  }
  EXPECT_TRUE(reused);
}

TEST_F(TopicTest, SpinThenSleepSpinsOnlyItsBudgetWhenIdle) {
  TopicConfig c = config(4, 64, Policy::kKeepLast);
  c.spin_us = 200;
  Publisher pub = make_pub(c);
  Subscriber sub = make_sub();
  EXPECT_EQ(sub.config().spin_us, 200u);
  timespec t0{}, t1{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t0);
  EXPECT_EQ(sub.take(1s).error(), Error::kTimeout);
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t1);
  const double cpu_ms = (t1.tv_sec - t0.tv_sec) * 1e3 + (t1.tv_nsec - t0.tv_nsec) / 1e6;
  // 200 µs of spinning, then futex sleeps with a liveness check every 5 ms:
  // about 2 ms of CPU. A reader that kept spinning would burn the whole
  // second; a tenth leaves room for a loaded machine's stray costs.
  EXPECT_LT(cpu_ms, 100.0) << "an idle spin-then-sleep reader must not burn its core";
  std::thread writer([&] {
    std::this_thread::sleep_for(20ms);
    send(pub, 5);
  });
  auto s = sub.take(5s);
  writer.join();
  ASSERT_TRUE(s.has_value());
  EXPECT_EQ(first_byte(*s), 5) << "a message after the spin budget still wakes the sleeper";
}

TEST_F(TopicTest, SpinBudgetIsBounded) {
  TopicConfig c = config(4, 64, Policy::kKeepLast);
  c.spin_us = 10'001;
  auto p = PublisherBuilder().run_id(run_).topic("telemetry/joint_state").config(c).create();
  EXPECT_EQ(p.error(), Error::kInvalidArgument);
}

}  // namespace
}  // namespace plr::shm
