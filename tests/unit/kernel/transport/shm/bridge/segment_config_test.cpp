// The geometry of a pipeline's segments (kernel/transport/shm/bridge/
// segment_config.cpp): slots sized from each message type's declared bound
// unless the config sets slot_size, and a world as large as an unloading run
// sends still crosses the `world` topic's ring.
#include "segment_config.hpp"
#include "pipeline_config.hpp"
#include "slot_size.hpp"
#include "test_util.hpp"

#include <plr/message.hpp>
#include <plr/messages.hpp>
#include <plr/shm/shm.hpp>

#include <gtest/gtest.h>

#include <cstring>
#include <vector>

namespace plr::kernel {
namespace {

using namespace std::chrono_literals;

constexpr std::size_t kWorldBound = 512 * 1024;  // WorldState's max_bytes (world.fbs)

PipelineConfig config(const std::string& topics = "") {
  auto c = parse_pipeline_config(
      "hosts:\n  sim: {restart: never}\n"
      "nodes:\n  a: {plugin: x}\n  b: {plugin: x, host: sim}\n" +
          (topics.empty() ? "" : "topics:\n" + topics),
      "segment_config_test.yaml");
  EXPECT_TRUE(c.has_value()) << c.error().message;
  return *c;
}

// A WorldState of `boxes` boxes and an octree of `octree_bytes`, a robot of 8 joints.
flatbuffers::DetachedBuffer world(std::size_t boxes, std::size_t octree_bytes) {
  flatbuffers::FlatBufferBuilder fbb;
  std::vector<msg::BoxState> states;
  std::vector<std::uint32_t> held;
  for (std::size_t i = 0; i < boxes; ++i) {
    states.emplace_back(static_cast<std::uint32_t>(i), msg::Vec3(0.4, 0.3, 0.3),
                        msg::Pose(msg::Vec3(1.0 * i, 0.5, 0.2), msg::Quat(0, 0, 0, 1)), 12.5);
    if (i % 10 == 0) held.push_back(static_cast<std::uint32_t>(i));
  }
  std::vector<std::uint8_t> octree(octree_bytes);
  for (std::size_t i = 0; i < octree.size(); ++i) octree[i] = static_cast<std::uint8_t>(i * 7);
  const std::vector<double> joints(8, 0.25);
  const msg::Vec3 trailer(2.5, 2.7, 16.0);
  fbb.Finish(msg::CreateWorldStateDirect(fbb, 1, &trailer, &octree, 0.05, &states,
                                         msg::CreateJointStateDirect(fbb, &joints, &joints), &held,
                                         3, true));
  return fbb.Release();
}

TEST(SegmentConfig, TopicSlotsAreSizedFromTheMessageTypesBound) {
  const auto c = config();
  const auto w = topic_segment_config(c.topic("world"), MessageTraits<msg::WorldState>::type_id());
  EXPECT_EQ(w.slot_size, kWorldBound);
  EXPECT_EQ(w.slot_count, 64u) << "the default depth";
  EXPECT_EQ(topic_segment_config(c.topic("clock"), MessageTraits<msg::Clock>::type_id()).slot_size,
            256u);
  // A type the SDK does not know, or one without a bound: the old default.
  EXPECT_EQ(topic_segment_config(c.topic("x"), 12345).slot_size, kDefaultSlotSize);
  EXPECT_EQ(topic_segment_config(c.topic("x"), MessageTraits<msg::Strategy>::type_id()).slot_size,
            kDefaultSlotSize);
}

TEST(SegmentConfig, AnExplicitSlotSizeWins) {
  const auto c = config("  world: {slot_size: 2048, depth: 4}\n  sim/observe: {slot_size: 4096}\n");
  const auto w = topic_segment_config(c.topic("world"), MessageTraits<msg::WorldState>::type_id());
  EXPECT_EQ(w.slot_size, 2048u);
  EXPECT_EQ(w.slot_count, 4u);
  const auto s =
      service_segment_config(c.topic("sim/observe"), MessageTraits<msg::ObserveRequest>::type_id(),
                             MessageTraits<msg::WorldState>::type_id(), 2);
  EXPECT_EQ(s.slot_size, 4096u);
}

TEST(SegmentConfig, AServiceHoldsTheLargerOfRequestAndReplyAndTwoChannelsPerOtherHost) {
  const auto c = config();
  const auto s =
      service_segment_config(c.topic("sim/observe"), MessageTraits<msg::ObserveRequest>::type_id(),
                             MessageTraits<msg::WorldState>::type_id(), 2);
  EXPECT_EQ(s.slot_size, kWorldBound);
  EXPECT_EQ(s.max_clients, 2u);
  EXPECT_EQ(service_segment_config(c.topic("plan"), MessageTraits<msg::PlanRequest>::type_id(),
                                   MessageTraits<msg::PlanResponse>::type_id(), 4)
                .max_clients,
            6u);
}

// More than the simulator sends on `world` (env C: 157 boxes and the octree
// of a 16 m trailer's walls, 93,528 bytes): 250 boxes and a 160 KiB octree.
// And the largest the bound is for.
TEST(SegmentConfig, ALargeWorldCrossesTheWorldTopicsRingAndALargerOneIsRefused) {
  const auto c = config();
  const auto geometry =
      topic_segment_config(c.topic("world"), MessageTraits<msg::WorldState>::type_id());
  const std::string run = shm::test::unique_run_id();
  auto pub = shm::PublisherBuilder().run_id(run).topic("sim/world").config(geometry).create();
  ASSERT_TRUE(pub) << shm::to_string(pub.error());
  auto sub = shm::SubscriberBuilder().run_id(run).topic("sim/world").create();
  ASSERT_TRUE(sub) << shm::to_string(sub.error());
  const shm::MessageType type{MessageTraits<msg::WorldState>::type_id(), 1};
  for (const auto& [boxes, octree] : {std::pair{250, 160 * 1024}, std::pair{2000, 256 * 1024}}) {
    const auto m = world(boxes, octree);
    ASSERT_LE(m.size(), kWorldBound) << boxes << " boxes";
    ASSERT_TRUE(pub->publish_copy(type, {reinterpret_cast<const std::byte*>(m.data()), m.size()}));
    auto got = sub->take(1s);
    ASSERT_TRUE(got) << shm::to_string(got.error());
    ASSERT_EQ(got->data().size(), m.size());
    EXPECT_EQ(std::memcmp(got->data().data(), m.data(), m.size()), 0);
    EXPECT_TRUE(verify<msg::WorldState>(reinterpret_cast<const std::uint8_t*>(got->data().data()),
                                        got->data().size()));
  }
  const auto too_big = world(250, kWorldBound);
  auto refused =
      pub->publish_copy(type, {reinterpret_cast<const std::byte*>(too_big.data()), too_big.size()});
  ASSERT_FALSE(refused);
  EXPECT_EQ(refused.error(), shm::Error::kTooLarge);
}

}  // namespace
}  // namespace plr::kernel
