// A Foxglove WebSocket client (foxglove.websocket.v1) against the monitor in
// a running pipeline. In the demo pipeline it is advertised PLR's topics as
// channels with their binary schemas, subscribes to two, and decodes the
// message frames with the reflection schema it was sent (not with PLR's
// generated code). In the small unloading run it reads the scene channel,
// checks every message against the JSON Schema it was advertised with, and
// compares the boxes with the world the simulator published.
#include "json_schema_check.hpp"
#include "pipeline_process.hpp"
#include "web_client.hpp"

#include <plr/message.hpp>
#include <plr/messages.hpp>
#include <plr/sim/unaligned.hpp>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <flatbuffers/reflection.h>

#include <map>
#include <set>
#include <stdexcept>

namespace plr::monitor_web::testing {
namespace {

std::uint64_t read_le(const std::string& s, std::size_t at, int bytes) {
  std::uint64_t v = 0;
  for (int i = bytes - 1; i >= 0; --i) v = v << 8 | static_cast<std::uint8_t>(s[at + i]);
  return v;
}

struct Decoder {
  std::string bfbs;
  std::string schema_name;
  const reflection::Schema& schema() const { return *reflection::GetSchema(bfbs.data()); }
  const reflection::Object* table() const {
    for (const auto* o : *schema().objects())
      if (o->name()->str() == schema_name) return o;
    return nullptr;
  }
};

class Foxglove : public ::testing::Test {
 protected:
  void SetUp() override {
    pipeline_ = std::make_unique<PipelineProcess>(
        PLR_BIN, std::vector<std::string>{
                     DEMO_CONFIG, "--duration", "60", "--set",
                     "pipeline=monitor_fox_" + std::to_string(::getpid()), "--set",
                     "nodes.counter.params.limit=100000", "--set",
                     "nodes.monitor={plugin: monitor_web, params: {port: 0, draw_robot: false}}"});
    port_ = pipeline_->monitor_port();
    ASSERT_NE(port_, 0) << pipeline_->log();
  }

  std::unique_ptr<PipelineProcess> pipeline_;
  std::uint16_t port_ = 0;
};

TEST_F(Foxglove, AClientDecodesMessagesOfTwoTopics) {
  WsClient client("127.0.0.1", port_, "/", "foxglove.websocket.v1");
  EXPECT_EQ(client.handshake_response()[http::field::sec_websocket_protocol],
            "foxglove.websocket.v1");

  // serverInfo first, then channels: `count` comes with the kernel's telemetry.
  std::map<std::string, nlohmann::json> channels;
  auto first = client.read();
  ASSERT_TRUE(first && !first->binary);
  EXPECT_EQ(nlohmann::json::parse(first->data).at("op"), "serverInfo");
  for (int i = 0; i < 20 && !(channels.count("count") && channels.count("kernel/telemetry")); ++i) {
    auto m = client.read();
    ASSERT_TRUE(m) << "no advertise for count and kernel/telemetry\n" << pipeline_->log();
    if (m->binary) continue;
    const auto j = nlohmann::json::parse(m->data);
    if (j.at("op") != "advertise") continue;
    for (const auto& c : j.at("channels")) channels[c.at("topic").get<std::string>()] = c;
  }
  const auto& count = channels.at("count");
  const auto& telemetry = channels.at("kernel/telemetry");
  for (const auto* c : {&count, &telemetry}) {
    EXPECT_EQ(c->at("encoding"), "flatbuffer");
    EXPECT_EQ(c->at("schemaEncoding"), "flatbuffer");
  }
  EXPECT_EQ(count.at("schemaName"), "plr.msg.Count");
  EXPECT_EQ(telemetry.at("schemaName"), "plr.msg.KernelTelemetry");

  std::map<std::uint32_t, Decoder> decoders;
  decoders[7] = {unbase64(count.at("schema")), "plr.msg.Count"};
  decoders[9] = {unbase64(telemetry.at("schema")), "plr.msg.KernelTelemetry"};
  for (auto& [id, d] : decoders) {
    flatbuffers::Verifier v(reinterpret_cast<const std::uint8_t*>(d.bfbs.data()), d.bfbs.size());
    ASSERT_TRUE(reflection::VerifySchemaBuffer(v)) << d.schema_name;
    ASSERT_NE(d.table(), nullptr) << d.schema_name;
  }
  client.send_text(nlohmann::json{{"op", "subscribe"},
                                  {"subscriptions",
                                   {{{"id", 7}, {"channelId", count.at("id")}},
                                    {{"id", 9}, {"channelId", telemetry.at("id")}}}}}
                       .dump());

  std::vector<std::int64_t> counts;
  std::vector<std::string> kernels;
  for (int i = 0; i < 400 && (counts.size() < 5 || kernels.empty()); ++i) {
    auto m = client.read();
    ASSERT_TRUE(m) << pipeline_->log();
    if (!m->binary) continue;
    ASSERT_GE(m->data.size(), 13u);
    ASSERT_EQ(m->data[0], 1) << "opcode: message data";
    const auto sub = static_cast<std::uint32_t>(read_le(m->data, 1, 4));
    EXPECT_GT(read_le(m->data, 5, 8), 0u) << "receive timestamp";
    ASSERT_TRUE(decoders.count(sub)) << "unknown subscription " << sub;
    const auto& d = decoders[sub];
    // The payload follows a 13-byte header: read from a copy, aligned.
    const std::string payload = m->data.substr(13);
    const auto* data = reinterpret_cast<const std::uint8_t*>(payload.data());
    const auto size = payload.size();
    ASSERT_TRUE(flatbuffers::Verify(d.schema(), *d.table(), data, size)) << d.schema_name;
    const auto& root = *flatbuffers::GetAnyRoot(data);
    if (sub == 7) {
      counts.push_back(
          flatbuffers::GetFieldI<std::int64_t>(root, *d.table()->fields()->LookupByKey("value")));
    } else {
      kernels.push_back(
          flatbuffers::GetFieldS(root, *d.table()->fields()->LookupByKey("kernel"))->str());
    }
  }
  ASSERT_GE(counts.size(), 5u);
  for (std::size_t i = 1; i < counts.size(); ++i) EXPECT_EQ(counts[i], counts[i - 1] + 1);
  ASSERT_FALSE(kernels.empty());
  EXPECT_EQ(kernels[0].rfind("monitor_fox_", 0), 0u) << kernels[0];
}

TEST_F(Foxglove, ItIsReadOnlyAndSaysWhatItRefuses) {
  WsClient client("127.0.0.1", port_, "/", "foxglove.websocket.v1");
  ASSERT_TRUE(client.read());  // serverInfo
  client.send_text(R"({"op":"advertise","channels":[{"id":1,"topic":"count"}]})");
  client.send_text(R"({"op":"subscribe","subscriptions":[{"id":1,"channelId":4242}]})");
  std::vector<std::string> statuses;
  for (int i = 0; i < 20 && statuses.size() < 2; ++i) {
    auto m = client.read();
    ASSERT_TRUE(m);
    if (m->binary) continue;
    const auto j = nlohmann::json::parse(m->data);
    if (j.at("op") == "status") statuses.push_back(j.at("message"));
  }
  ASSERT_EQ(statuses.size(), 2u);
  EXPECT_EQ(statuses[0], "unsupported operation 'advertise' (this server is read-only)");
  EXPECT_EQ(statuses[1], "subscribe: no channel 4242");
}

// The boxes of one world, as the scene should show them.
struct WorldBoxes {
  std::map<std::string, nlohmann::json> cubes;  // entity id -> {pose, size}
};

WorldBoxes decode_world(const std::string& payload) {
  WorldBoxes out;
  const auto* data = reinterpret_cast<const std::uint8_t*>(payload.data());
  if (!plr::verify<msg::WorldState>(data, payload.size()))
    throw std::runtime_error("world: not a WorldState");
  const auto& w = *flatbuffers::GetRoot<msg::WorldState>(data);
  if (!w.boxes()) return out;
  for (flatbuffers::uoffset_t i = 0; i < w.boxes()->size(); ++i) {
    const msg::BoxState b = sim::element(*w.boxes(), i);
    const auto& p = b.pose().position();
    const auto& q = b.pose().orientation();
    out.cubes["box/" + std::to_string(b.id())] = {
        {"pose",
         {{"position", {{"x", p.x()}, {"y", p.y()}, {"z", p.z()}}},
          {"orientation", {{"x", q.x()}, {"y", q.y()}, {"z", q.z()}, {"w", q.w()}}}}},
        {"size", {{"x", b.size().x()}, {"y", b.size().y()}, {"z", b.size().z()}}}};
  }
  return out;
}

TEST(FoxgloveSceneChannel, EveryMessageMatchesItsSchemaAndTheWorld) {
  // Paced at 5x the robot's speed, so the run lasts while the client reads.
  PipelineProcess run(PLR_BIN, {UNLOAD_SMALL_CONFIG, "--report", "{dir}/report", "--set",
                                "pipeline=monitor_scene_" + std::to_string(::getpid()), "--set",
                                "nodes.simulator.params.real_time_factor=5", "--set",
                                "nodes.monitor={plugin: monitor_web, params: {port: 0}}"});
  const auto port = run.monitor_port();
  ASSERT_NE(port, 0) << run.log();
  WsClient client("127.0.0.1", port, "/", "foxglove.websocket.v1");

  std::map<std::string, nlohmann::json> channels;
  for (int i = 0; i < 20 && !(channels.count("/scene") && channels.count("world")); ++i) {
    auto m = client.read();
    ASSERT_TRUE(m) << "no advertise for /scene and world\n" << run.log();
    if (m->binary) continue;
    const auto j = nlohmann::json::parse(m->data);
    if (j.at("op") != "advertise") continue;
    for (const auto& c : j.at("channels")) channels[c.at("topic").get<std::string>()] = c;
  }
  const auto& scene = channels.at("/scene");
  EXPECT_EQ(scene.at("encoding"), "json");
  EXPECT_EQ(scene.at("schemaEncoding"), "jsonschema");
  EXPECT_EQ(scene.at("schemaName"), "foxglove.SceneUpdate");
  const auto schema = nlohmann::json::parse(scene.at("schema").get<std::string>());
  client.send_text(nlohmann::json{{"op", "subscribe"},
                                  {"subscriptions",
                                   {{{"id", 1}, {"channelId", scene.at("id")}},
                                    {{"id", 2}, {"channelId", channels.at("world").at("id")}}}}}
                       .dump());

  std::map<std::uint64_t, WorldBoxes> worlds;  // by bus stamp
  std::set<std::string> shown;                 // box entities of the previous scene
  std::size_t scenes = 0, matched = 0, deleted = 0, robot_entities = 0;
  for (int i = 0; i < 5000 && (matched < 10 || deleted < 3); ++i) {
    auto m = client.read();
    ASSERT_TRUE(m) << "scenes " << scenes << ", matched " << matched << ", deleted " << deleted
                   << "\n"
                   << run.log();
    if (!m->binary) continue;
    ASSERT_GE(m->data.size(), 13u);
    const auto sub = read_le(m->data, 1, 4);
    const auto stamp = read_le(m->data, 5, 8);
    const std::string payload = m->data.substr(13);
    if (sub == 2) {
      worlds[stamp] = decode_world(payload);
      continue;
    }
    ASSERT_EQ(sub, 1u);
    ++scenes;
    const auto j = nlohmann::json::parse(payload);
    ASSERT_EQ(schema_violation(schema, j, true), "") << "scene " << scenes;

    std::map<std::string, nlohmann::json> boxes;
    std::size_t robot = 0;
    for (const auto& e : j.at("entities")) {
      const std::string id = e.at("id");
      EXPECT_EQ(e.at("frame_id"), "trailer");
      EXPECT_EQ(e.at("timestamp").at("sec").get<std::uint64_t>() * 1'000'000'000 +
                    e.at("timestamp").at("nsec").get<std::uint64_t>(),
                stamp);
      if (id.rfind("box/", 0) == 0) {
        ASSERT_EQ(e.at("cubes").size(), 1u) << id;
        boxes[id] = e.at("cubes")[0];
      }
      robot += id.rfind("robot/", 0) == 0;
    }
    EXPECT_GT(robot, 0u);
    if (robot_entities == 0) robot_entities = robot;
    EXPECT_EQ(robot, robot_entities) << "the robot's entities stay the same";
    // Boxes that left since the previous scene are deleted by id, no other.
    std::set<std::string> gone;
    for (const auto& id : shown)
      if (!boxes.count(id)) gone.insert(id);
    std::set<std::string> deletions;
    for (const auto& d : j.at("deletions")) {
      EXPECT_EQ(d.at("type"), 0);
      deletions.insert(d.at("id").get<std::string>());
    }
    if (scenes > 1) {
      EXPECT_EQ(deletions, gone) << "scene " << scenes;
    }
    deleted += gone.size();
    shown.clear();
    for (const auto& [id, c] : boxes) shown.insert(id);

    // The world it was made of came first on the world channel (unless the
    // scene was sent on subscribing, before that world's frame).
    const auto w = worlds.find(stamp);
    if (w == worlds.end()) continue;
    ++matched;
    ASSERT_EQ(boxes.size(), w->second.cubes.size()) << "scene " << scenes;
    for (const auto& [id, want] : w->second.cubes) {
      ASSERT_TRUE(boxes.count(id)) << id;
      EXPECT_EQ(boxes.at(id).at("pose"), want.at("pose")) << id;
      EXPECT_EQ(boxes.at(id).at("size"), want.at("size")) << id;
    }
  }
  EXPECT_GE(matched, 10u);
  EXPECT_GE(deleted, 3u);
  // Only a new world makes a scene (the first one: the subscription).
  EXPECT_LE(scenes, worlds.size() + 1);
}

}  // namespace
}  // namespace plr::monitor_web::testing
