// A pipeline's /dev/shm need (kernel/core/shm_need.cpp), counted from what
// its plug-ins declare: the same segments, of the same size, as a run makes.
#include "shm_need.hpp"
#include "pipeline_config.hpp"
#include "segment_config.hpp"

#include <plr/interface.hpp>
#include <plr/message.hpp>
#include <plr/messages.hpp>
#include <plr/shm/shm.hpp>

#include <gtest/gtest.h>

namespace plr::kernel {
namespace {

PipelineConfig config(const std::string& yaml) {
  auto c = parse_pipeline_config(yaml, "shm_need_test.yaml");
  EXPECT_TRUE(c.has_value()) << c.error().message;
  return *c;
}

const plr_port kSimPorts[] = {
    topic<msg::WorldState>("world"),
    service<msg::ObserveRequest, msg::WorldState>("sim/observe"),
};
const plr_interface kSim = {2, kSimPorts};

const plr_port kExecutorPorts[] = {topic<msg::PipelineDone>("pipeline/done")};
const plr_interface kExecutor = {1, kExecutorPorts};

const char* kTwoHosts =
    "hosts:\n  sim: {restart: never}\n"
    "nodes:\n  sim: {plugin: s, host: sim}\n  executor: {plugin: e}\n";

std::size_t topic_bytes(const PipelineConfig& c, const std::string& name, std::uint64_t type) {
  return shm::segment_bytes(topic_segment_config(c.topic(name), type));
}

const SegmentNeed* find(const ShmNeed& need, const std::string& host, const std::string& name) {
  for (const auto& s : need.segments)
    if (s.host == host && s.name == name) return &s;
  return nullptr;
}

TEST(ShmNeed, ARunOnOneHostNeedsNone) {
  const auto c = config("nodes:\n  sim: {plugin: s}\n  executor: {plugin: e}\n");
  const auto need = shm_need(c, {{"sim", &kSim}, {"executor", &kExecutor}});
  EXPECT_EQ(need.total, 0u);
  EXPECT_TRUE(need.segments.empty());
}

TEST(ShmNeed, EachHostCountsItsTelemetryAndItsNodesDeclaredTopicsAndServices) {
  const auto c = config(kTwoHosts);
  const auto need = shm_need(c, {{"sim", &kSim}, {"executor", &kExecutor}});
  ASSERT_EQ(need.segments.size(), 5u);
  const auto* world = find(need, "sim", "world");
  ASSERT_NE(world, nullptr);
  EXPECT_EQ(world->slot_size, 512u * 1024) << "WorldState's bound";
  EXPECT_EQ(world->slots, 64u);
  EXPECT_EQ(world->bytes, topic_bytes(c, "world", MessageTraits<msg::WorldState>::type_id()));
  const auto* observe = find(need, "sim", "sim/observe");
  ASSERT_NE(observe, nullptr);
  EXPECT_TRUE(observe->service);
  EXPECT_EQ(observe->slot_size, 512u * 1024) << "the larger of request and reply";
  EXPECT_EQ(observe->slots, 2u * 2 * 4) << "two channels for the one other host, 4 slots a ring";
  const auto* done = find(need, "main", "pipeline/done");
  ASSERT_NE(done, nullptr);
  EXPECT_EQ(done->slot_size, 4096u);
  for (const auto* host : {"main", "sim"}) {
    const auto* t = find(need, host, "kernel/telemetry");
    ASSERT_NE(t, nullptr) << host;
    EXPECT_EQ(t->slot_size, 64u * 1024);
  }
  std::size_t sum = 0;
  for (const auto& s : need.segments) sum += s.bytes;
  EXPECT_EQ(need.total, sum);
  EXPECT_TRUE(need.undeclared.empty());
}

TEST(ShmNeed, RemapsDepthsAndExplicitSlotSizesApply) {
  const auto c = config(
      "hosts:\n  sim: {restart: never}\n"
      "nodes:\n  sim: {plugin: s, host: sim}\n"
      "  executor: {plugin: e, remap: {pipeline/done: run/done}}\n"
      "topics:\n  world: {depth: 8}\n  run/done: {slot_size: 100000}\n");
  const auto need = shm_need(c, {{"sim", &kSim}, {"executor", &kExecutor}});
  const auto* world = find(need, "sim", "world");
  ASSERT_NE(world, nullptr);
  EXPECT_EQ(world->slots, 8u);
  EXPECT_EQ(find(need, "main", "pipeline/done"), nullptr);
  const auto* done = find(need, "main", "run/done");
  ASSERT_NE(done, nullptr);
  EXPECT_EQ(done->slot_size, 100000u);
}

TEST(ShmNeed, ANodeWhosePluginDeclaresNothingIsNamedNotCounted) {
  const auto c = config(kTwoHosts);
  const auto need = shm_need(c, {{"sim", &kSim}, {"executor", nullptr}});
  EXPECT_EQ(need.undeclared, std::vector<std::string>{"executor"});
  EXPECT_EQ(need.segments.size(), 4u) << "both telemetry topics and the simulator's two";
}

TEST(ShmNeed, BytesAreShownForPeople) {
  EXPECT_EQ(format_bytes(512), "512 B");
  EXPECT_EQ(format_bytes(4096), "4.00 KiB");
  EXPECT_EQ(format_bytes(141422592), "134.9 MiB");
  EXPECT_EQ(format_bytes(std::size_t{1288} << 20), "1.26 GiB");
}

}  // namespace
}  // namespace plr::kernel
