// Untrusted envelopes: a raw DDS participant writes garbage on every topic a
// kernel listens to. Nothing crashes, each bad envelope is counted, a good
// request still gets its reply, and a remote command is refused (remote
// control is off by default).
#include "dds_bridge.hpp"
#include "envelope.h"
#include "kernel.hpp"

#include <plr/message.hpp>
#include <plr/messages.hpp>

#include <gtest/gtest.h>

#include <unistd.h>
#include <optional>
#include <thread>

namespace plr::kernel {
namespace {

using namespace std::chrono_literals;

class Raw {
 public:
  explicit Raw(int domain) {
    DdsConfig c;
    c.domain = domain;
    auto p = open_participant(c);
    EXPECT_TRUE(p) << p.error().message;
    participant_ = p ? *p : 0;
  }
  ~Raw() {
    if (participant_ > 0) dds_delete(participant_);
  }
  dds_entity_t endpoint(const std::string& topic, bool writer) {
    const auto t =
        dds_create_topic(participant_, &plr_dds_Envelope_desc, topic.c_str(), nullptr, nullptr);
    dds_qos_t* q = dds_create_qos();
    dds_qset_reliability(q, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
    dds_qset_history(q, DDS_HISTORY_KEEP_ALL, 0);
    const auto e = writer ? dds_create_writer(participant_, t, q, nullptr)
                          : dds_create_reader(participant_, t, q, nullptr);
    dds_delete_qos(q);
    return e;
  }
  static void wait_matched(dds_entity_t writer) {
    for (int i = 0; i < 500; ++i) {
      dds_publication_matched_status_t m{};
      dds_get_publication_matched_status(writer, &m);
      if (m.current_count > 0) return;
      std::this_thread::sleep_for(10ms);
    }
    FAIL() << "writer never matched";
  }

 private:
  dds_entity_t participant_ = 0;
};

struct Env {
  std::string kernel = "raw@test:1", target = {}, name = {};
  std::uint8_t kind = 0;
  std::uint64_t type_id = 0, corr = 0;
  std::vector<std::uint8_t> payload = {};

  void write(dds_entity_t w) {
    plr_dds_Envelope e{};
    e.kernel = const_cast<char*>(kernel.c_str());
    e.target = const_cast<char*>(target.c_str());
    e.name = const_cast<char*>(name.c_str());
    e.kind = kind;
    e.type_id = type_id;
    e.correlation_id = corr;
    e.payload._buffer = payload.data();
    e.payload._length = e.payload._maximum = static_cast<std::uint32_t>(payload.size());
    ASSERT_EQ(dds_write(w, &e), DDS_RETCODE_OK);
  }
};

std::vector<std::uint8_t> double_request(std::int64_t v) {
  flatbuffers::FlatBufferBuilder fbb;
  fbb.Finish(msg::CreateDoubleRequest(fbb, v));
  return {fbb.GetBufferPointer(), fbb.GetBufferPointer() + fbb.GetSize()};
}

// Replies addressed to "raw@test:1", by correlation id: (kind, status, payload).
struct Reply {
  std::uint8_t kind;
  std::int32_t status;
  std::vector<std::uint8_t> payload;
};
std::map<std::uint64_t, Reply> take_replies(dds_entity_t reader, std::size_t want) {
  std::map<std::uint64_t, Reply> out;
  for (int i = 0; i < 300 && out.size() < want; ++i) {
    void* samples[16] = {};
    dds_sample_info_t infos[16];
    const auto n = dds_take(reader, samples, infos, 16, 16);
    for (int k = 0; k < n; ++k) {
      const auto& e = *static_cast<const plr_dds_Envelope*>(samples[k]);
      if (infos[k].valid_data && std::string(e.target) == "raw@test:1")
        out[e.correlation_id] = {
            e.kind, e.status, {e.payload._buffer, e.payload._buffer + e.payload._length}};
    }
    if (n > 0) dds_return_loan(reader, samples, n);
    std::this_thread::sleep_for(10ms);
  }
  return out;
}

TEST(RemoteEnvelope, GarbageIsCountedGoodRequestsAnsweredCommandsRefused) {
  const int domain = 100 + (::getpid() + 50) % 100;
  auto config = parse_pipeline_config(
      "pipeline: garbage\nnodes:\n  doubler: {plugin: demo_doubler}\nremote:\n  dds: {domain: " +
          std::to_string(domain) + ", export: [double], import: [count]}\n",
      "garbage.yaml");
  ASSERT_TRUE(config) << config.error().message;
  Kernel kernel(*config);
  ASSERT_TRUE(kernel.start());
  ASSERT_TRUE(kernel.sync_transports());
  const auto telemetry = [&] { return nlohmann::json::parse(kernel.telemetry_json()); };
  const std::string id = telemetry()["dds"]["kernel"];

  Raw raw(domain);
  const auto count_w = raw.endpoint(dds_topic_name("count"), true);
  const auto request_w = raw.endpoint(kDdsRequestTopic, true);
  const auto announce_w = raw.endpoint(kDdsAnnounceTopic, true);
  const auto control_w = raw.endpoint(kDdsControlTopic, true);
  const auto reply_r = raw.endpoint(kDdsReplyTopic, false);
  const auto result_r = raw.endpoint(kDdsResultTopic, false);
  for (auto w : {count_w, request_w, announce_w, control_w}) Raw::wait_matched(w);

  const auto count_type = MessageTraits<msg::Count>::type_id();
  int bad = 0;
  // On the count topic: wrong kind, wrong name, wrong type, empty sender,
  // oversized name, payload beyond slot_size.
  Env{.name = "count", .kind = 2, .type_id = count_type}.write(count_w), ++bad;
  Env{.name = "other", .kind = 0, .type_id = count_type}.write(count_w), ++bad;
  Env{.name = "count", .kind = 0, .type_id = 42}.write(count_w), ++bad;
  Env{.kernel = "", .name = "count", .kind = 0, .type_id = count_type}.write(count_w), ++bad;
  Env{.name = std::string(5000, 'x'), .kind = 0}.write(count_w), ++bad;
  Env{.name = "count", .kind = 99}.write(count_w), ++bad;
  Env{.name = "count",
      .kind = 0,
      .type_id = count_type,
      .payload = std::vector<std::uint8_t>((1 << 20) + 1, 0xab)}
      .write(count_w),
      ++bad;
  // Right envelope, garbage FlatBuffer: passes the bridge, the SDK rejects it.
  Env{.name = "count", .kind = 0, .type_id = count_type, .payload = {1, 2, 3, 4, 5, 6, 7}}.write(
      count_w);
  // Announces that are not JSON.
  Env{.name = "announce", .kind = 4, .payload = {'{', 'x'}}.write(announce_w), ++bad;

  // Requests: a good one, a garbage payload, an unknown service.
  Env{.target = id,
      .name = "double",
      .kind = 1,
      .type_id = MessageTraits<msg::DoubleRequest>::type_id(),
      .corr = 1,
      .payload = double_request(21)}
      .write(request_w);
  Env{.target = id,
      .name = "double",
      .kind = 1,
      .type_id = MessageTraits<msg::DoubleRequest>::type_id(),
      .corr = 2,
      .payload = {9, 9, 9}}
      .write(request_w);
  Env{.target = id, .name = "nope", .kind = 1, .type_id = 1, .corr = 3, .payload = {1}}.write(
      request_w);
  // A remote swap: remote control is off.
  const std::string cmd = R"({"cmd":"swap","node":"doubler","plugin":"demo_doubler"})";
  Env{.target = id, .name = "swap", .kind = 6, .corr = 4, .payload = {cmd.begin(), cmd.end()}}
      .write(control_w);

  const auto replies = take_replies(reply_r, 3);
  ASSERT_EQ(replies.size(), 3u);
  ASSERT_EQ(replies.at(1).kind, static_cast<std::uint8_t>(EnvelopeKind::kReply));
  const auto& p = replies.at(1).payload;
  ASSERT_TRUE(verify<msg::DoubleReply>(p.data(), p.size()));
  EXPECT_EQ(flatbuffers::GetRoot<msg::DoubleReply>(p.data())->value(), 42);
  EXPECT_EQ(replies.at(2).kind, static_cast<std::uint8_t>(EnvelopeKind::kError));
  EXPECT_EQ(replies.at(3).kind, static_cast<std::uint8_t>(EnvelopeKind::kError));
  EXPECT_NE(std::string(replies.at(3).payload.begin(), replies.at(3).payload.end())
                .find("does not export service 'nope'"),
            std::string::npos);

  const auto results = take_replies(result_r, 1);
  ASSERT_EQ(results.count(4), 1u);
  EXPECT_EQ(results.at(4).status, PLR_ERR_STATE);
  EXPECT_NE(std::string(results.at(4).payload.begin(), results.at(4).payload.end())
                .find("refuses remote control"),
            std::string::npos);

  auto t = telemetry();
  for (int i = 0; i < 100 && t["dds"]["invalid"].get<int>() < bad; ++i) {
    std::this_thread::sleep_for(20ms);
    t = telemetry();
  }
  EXPECT_EQ(t["dds"]["invalid"].get<int>(), bad) << t.dump(2);
  EXPECT_EQ(t["dds"]["commands_refused"].get<int>(), 1);
  // The garbage FlatBuffer and the garbage request: caught by the SDK's verifier.
  EXPECT_GE(t["invalid_messages"].get<int>(), 1) << t.dump(2);
  EXPECT_EQ(kernel.nodes()[0].state, "active");
  kernel.stop();
}

}  // namespace
}  // namespace plr::kernel
