// The ring alone, in this process's memory: its geometry limits, order,
// keep-last laps, reliable back-pressure and what a departing reader gives
// back. (Topics and services build on it: topic_test, service_test.)
#include "ring.hpp"
#include "layout.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <memory>

namespace plr::shm::detail {
namespace {

RingGeometry geometry(std::uint32_t slots, Policy policy) {
  return RingGeometry{slots, 64, 4, policy, WaitMode::kBlocking, 0};
}

// A ring over zeroed memory of its own.
struct LocalRing {
  explicit LocalRing(const RingGeometry& g)
      : memory(static_cast<std::byte*>(std::aligned_alloc(kLine, round(Ring::bytes(g))))) {
    std::memset(memory.get(), 0, round(Ring::bytes(g)));
    ring = Ring::init(memory.get(), g, nullptr);
  }
  static std::size_t round(std::size_t n) { return (n + kLine - 1) / kLine * kLine; }
  struct Free {
    void operator()(std::byte* p) const { std::free(p); }
  };
  std::unique_ptr<std::byte, Free> memory;
  Ring ring;
};

void publish(Producer& p, std::uint64_t type, std::uint8_t byte) {
  auto slot = p.loan(1, kNoWait);
  ASSERT_TRUE(slot) << to_string(slot.error());
  *p.ring().payload(*slot) = static_cast<std::byte>(byte);
  ASSERT_TRUE(p.publish(*slot, MessageType{type, 1}, 0, 0, 1));
}

TEST(Ring, GeometryOutsideTheLimitsIsRefused) {
  EXPECT_TRUE(Ring::check(geometry(16, Policy::kKeepLast)));
  auto bad = [](auto change) {
    RingGeometry g = geometry(16, Policy::kKeepLast);
    change(g);
    const auto r = Ring::check(g);
    return !r && r.error() == Error::kInvalidArgument;
  };
  EXPECT_TRUE(bad([](RingGeometry& g) { g.slot_count = 0; }));
  EXPECT_TRUE(bad([](RingGeometry& g) { g.slot_count = kMaxSlots + 1; }));
  EXPECT_TRUE(bad([](RingGeometry& g) { g.slot_size = 0; }));
  EXPECT_TRUE(bad([](RingGeometry& g) { g.max_subscribers = kMaxSubscribers + 1; }));
  EXPECT_TRUE(bad([](RingGeometry& g) { g.policy = static_cast<Policy>(7); }));
  EXPECT_TRUE(bad([](RingGeometry& g) { g.spin_us = kMaxSpinUs + 1; }));
}

TEST(Ring, AReaderTakesEachMessageOnceInOrder) {
  LocalRing r(geometry(8, Policy::kKeepLast));
  Producer p(r.ring);
  Consumer c(r.ring);
  ASSERT_TRUE(c.attach(ProcessStamp::self()));
  for (std::uint8_t i = 0; i < 3; ++i) publish(p, 42, i);
  for (std::uint64_t seq = 0; seq < 3; ++seq) {
    auto t = c.try_take();
    ASSERT_TRUE(t) << to_string(t.error());
    EXPECT_EQ(t->info.seq, seq);
    EXPECT_EQ(t->info.type_id, 42u);
    EXPECT_EQ(t->info.size, 1u);
    EXPECT_EQ(*r.ring.payload(t->slot), static_cast<std::byte>(seq)) << "read in place";
    release_slot(r.ring.slot(t->slot), c.bit(), r.ring.header->space);
  }
  const auto none = c.try_take();
  ASSERT_FALSE(none);
  EXPECT_EQ(none.error(), Error::kNoData);
  EXPECT_EQ(c.counters().received, 3u);
  EXPECT_EQ(p.published(), 3u);
}

TEST(Ring, KeepLastLapsASlowReaderAndCountsWhatItMissed) {
  LocalRing r(geometry(4, Policy::kKeepLast));
  Producer p(r.ring);
  Consumer c(r.ring);
  ASSERT_TRUE(c.attach(ProcessStamp::self()));
  for (std::uint8_t i = 0; i < 10; ++i) publish(p, 1, i);
  auto t = c.try_take();
  ASSERT_TRUE(t);
  EXPECT_EQ(t->info.seq, 6u) << "the oldest of the last four";
  EXPECT_EQ(c.counters().dropped_slow, 6u);
  release_slot(r.ring.slot(t->slot), c.bit(), r.ring.header->space);
}

// A reliable ring of two slots, both published, and one reader.
class FullReliableRing : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(c.attach(ProcessStamp::self()));
    publish(p, 1, 0);
    publish(p, 1, 1);
  }
  LocalRing r{geometry(2, Policy::kReliable)};
  Producer p{r.ring};
  Consumer c{r.ring};
};

TEST_F(FullReliableRing, ThePublisherWaitsForItsSlowestReader) {
  const auto full = p.loan(1, kNoWait);
  ASSERT_FALSE(full);
  EXPECT_EQ(full.error(), Error::kTimeout);
  auto t = c.try_take();
  ASSERT_TRUE(t);
  release_slot(r.ring.slot(t->slot), c.bit(), r.ring.header->space);
  auto slot = p.loan(1, kNoWait);
  ASSERT_TRUE(slot) << "the reader moved on";
  p.cancel(*slot);
}

TEST_F(FullReliableRing, AReaderThatLeavesGivesBackWhatItHeld) {
  ASSERT_TRUE(c.try_take()) << "taken and still held";
  c.detach();
  auto slot = p.loan(1, kNoWait);
  ASSERT_TRUE(slot) << "nobody reads any more";
  p.cancel(*slot);
}

TEST(Ring, TheReaderTableIsBounded) {
  LocalRing r(RingGeometry{4, 64, 2, Policy::kKeepLast, WaitMode::kBlocking, 0});
  Consumer a(r.ring), b(r.ring), c(r.ring);
  ASSERT_TRUE(a.attach(ProcessStamp::self()));
  ASSERT_TRUE(b.attach(ProcessStamp::self()));
  const auto third = c.attach(ProcessStamp::self());
  ASSERT_FALSE(third);
  EXPECT_EQ(third.error(), Error::kTooManySubscribers);
  a.detach();
  EXPECT_TRUE(c.attach(ProcessStamp::self())) << "a freed entry is reused";
}

}  // namespace
}  // namespace plr::shm::detail
