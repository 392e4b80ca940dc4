// The bus recorder: it subscribes the moment a topic is advertised, so even
// a topic's first message is in the file, and only the topics asked for.
#include "recorder.hpp"
#include "kernel_fixture.hpp"
#include "mcap_reader.hpp"

#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <map>

namespace plr::kernel {
namespace {

// Every topic reliable: a burst waits for the recorder instead of dropping.
TopicSettings reliable(const std::string& topic) {
  TopicSettings s;
  s.name = topic;
  s.policy = TopicPolicy::Reliable;
  return s;
}

TEST(Recorder, TopicPatterns) {
  EXPECT_TRUE(topic_matches("*", "world"));
  EXPECT_TRUE(topic_matches("executor/*", "executor/state"));
  EXPECT_FALSE(topic_matches("executor/*", "executors"));
  EXPECT_TRUE(topic_matches("*/state", "executor/state"));
  EXPECT_TRUE(topic_matches("a*b*c", "a12b34c"));
  EXPECT_FALSE(topic_matches("a*b*c", "a12c34b"));
  EXPECT_FALSE(topic_matches("world", "world2"));
}

TEST(Recorder, RecordsEveryMessageOfTheTopicsAskedFor) {
  const auto path =
      std::filesystem::temp_directory_path() / ("recorder_" + std::to_string(::getpid()) + ".mcap");
  // Reliable: the burst below waits for the recorder instead of dropping
  // (a subscriber like any other, it gets what the topic's policy lets through).
  Bus bus(reliable);
  testing::TestEndpoint node("node");
  bus.set_live(&node, true);
  auto recorder = Recorder::create(bus, path.string(), {"count", "other/*"});
  ASSERT_TRUE(recorder) << recorder.error().message;
  // Published right after advertising: no time for anything asynchronous.
  for (const char* topic : {"count", "doubled"}) {
    const auto publisher = bus.advertise(&node, topic, MessageTraits<msg::Count>::type_id(), 1);
    ASSERT_TRUE(publisher);
    for (int i = 0; i < 100; ++i) {
      flatbuffers::FlatBufferBuilder fbb;
      fbb.Finish(msg::CreateCount(fbb, i));
      ASSERT_TRUE(bus.publish(*publisher, testing::make_msg<msg::Count>(fbb)));
    }
  }
  ASSERT_TRUE((*recorder)->finish());
  EXPECT_EQ((*recorder)->messages(), 100u);
  recorder->reset();

  auto bytes = mcap::load(path.string());
  ASSERT_TRUE(bytes);
  mcap::Contents contents;
  std::vector<std::int64_t> values;
  ASSERT_TRUE(mcap::read(
      *bytes, path.string(),
      [&](const mcap::MessageRecord& m) {
        EXPECT_EQ(m.channel->topic, "count");
        // A record's bytes lie anywhere in the file: read from a copy.
        const std::string body(m.data);
        values.push_back(flatbuffers::GetRoot<msg::Count>(body.data())->value());
      },
      contents));
  ASSERT_EQ(values.size(), 100u);
  for (int i = 0; i < 100; ++i) EXPECT_EQ(values[i], i);
  ASSERT_EQ(contents.schemas.size(), 1u);
  EXPECT_EQ(contents.schemas.begin()->second.name, "plr.msg.Count");
  std::filesystem::remove(path);
  bus.remove_endpoint(&node);
}

// A long run's recording: split in parts, each complete and within the
// bound, the oldest beyond `keep` removed, the newest at the path asked for.
TEST(Recorder, ARecordingPastItsBoundIsSplitInPartsWithinIt) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("recorder_parts_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path path = dir / "run.mcap";
  Bus bus(reliable);
  testing::TestEndpoint node("node");
  bus.set_live(&node, true);
  constexpr std::uint64_t kMax = 1 << 20;
  auto recorder = Recorder::create(bus, path.string(), {"report"}, {kMax, 2});
  ASSERT_TRUE(recorder) << recorder.error().message;
  const auto publisher =
      bus.advertise(&node, "report", MessageTraits<msg::NodeReport>::type_id(), 1);
  ASSERT_TRUE(publisher);
  // 3000 messages of 2 KiB, numbered: about 6 MiB, six parts' worth.
  constexpr int kMessages = 3000;
  for (int i = 0; i < kMessages; ++i) {
    flatbuffers::FlatBufferBuilder fbb;
    fbb.Finish(msg::CreateNodeReportDirect(fbb, std::to_string(i).c_str(),
                                           std::string(2048, 'x').c_str()));
    ASSERT_TRUE(bus.publish(*publisher, testing::make_msg<msg::NodeReport>(fbb)));
  }
  ASSERT_TRUE((*recorder)->finish());
  EXPECT_EQ((*recorder)->messages(), static_cast<std::uint64_t>(kMessages));
  recorder->reset();

  EXPECT_FALSE(fs::exists(dir / "run.3.mcap"));
  std::vector<int> first, last;  // per part, oldest first: run.2, run.1, run
  for (const char* name : {"run.2.mcap", "run.1.mcap", "run.mcap"}) {
    const fs::path part = dir / name;
    ASSERT_TRUE(fs::exists(part)) << name;
    // The summary (schema, channel, chunk indexes) comes on top of the bound.
    EXPECT_LE(fs::file_size(part), kMax + (64u << 10)) << name;
    auto bytes = mcap::load(part.string());
    ASSERT_TRUE(bytes) << name;
    mcap::Contents contents;
    std::vector<int> ids;
    ASSERT_TRUE(mcap::read(
        *bytes, part.string(),
        [&](const mcap::MessageRecord& m) {
          EXPECT_EQ(m.channel->topic, "report");
          const std::string body(m.data);
          ids.push_back(
              std::stoi(flatbuffers::GetRoot<msg::NodeReport>(body.data())->node()->str()));
        },
        contents))
        << name;
    ASSERT_FALSE(ids.empty()) << name;
    for (std::size_t k = 1; k < ids.size(); ++k) EXPECT_EQ(ids[k], ids[k - 1] + 1) << name;
    first.push_back(ids.front());
    last.push_back(ids.back());
  }
  // Consecutive parts, the newest ending with the last message.
  EXPECT_EQ(first[1], last[0] + 1);
  EXPECT_EQ(first[2], last[1] + 1);
  EXPECT_EQ(last[2], kMessages - 1);
  fs::remove_all(dir);
  bus.remove_endpoint(&node);
}

}  // namespace
}  // namespace plr::kernel
