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
  Bus bus([](const std::string& topic) {
    TopicSettings s;
    s.name = topic;
    s.policy = TopicPolicy::Reliable;
    return s;
  });
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

}  // namespace
}  // namespace plr::kernel
