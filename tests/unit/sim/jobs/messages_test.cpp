#include <gtest/gtest.h>

#include "plr/jobs/messages.hpp"

namespace {

using plr::jobs::Bytes;

TEST(JobMessages, RequestAndReplyRoundTrip) {
  const plr::jobs::Job job{"test.echo", "a_key-1.x", {1, 2, 3, 0, 255}};
  const Bytes request = plr::jobs::encode_request(7, job);
  auto m = plr::jobs::decode_message(request.data(), request.size(), "test");
  ASSERT_TRUE(m) << m.error().message;
  EXPECT_EQ(m->type, plr::jobs::Message::Type::kRequest);
  EXPECT_EQ(m->id, 7u);
  EXPECT_EQ(m->job.kind, job.kind);
  EXPECT_EQ(m->job.key, job.key);
  EXPECT_EQ(m->job.input, job.input);

  plr::jobs::Result ok{"k", true, {9, 8}, "", 1.5, 2, false};
  const Bytes reply = plr::jobs::encode_reply(3, ok);
  auto r = plr::jobs::decode_message(reply.data(), reply.size(), "test");
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(r->type, plr::jobs::Message::Type::kReply);
  EXPECT_TRUE(r->result.ok);
  EXPECT_EQ(r->result.output, ok.output);
  EXPECT_EQ(r->result.attempts, 2u);
  EXPECT_DOUBLE_EQ(r->result.wall_s, 1.5);

  plr::jobs::Result failed{"k", false, {}, "it broke", 0.25, 1, false};
  const Bytes bad = plr::jobs::encode_reply(4, failed);
  auto f = plr::jobs::decode_message(bad.data(), bad.size(), "test");
  ASSERT_TRUE(f);
  EXPECT_FALSE(f->result.ok);
  EXPECT_EQ(f->result.error, "it broke");
}

TEST(JobMessages, RefuseKeysThatAreNoFileNames) {
  for (const char* key : {"", "../up", ".hidden", "a/b", "sp ace"}) {
    const Bytes m = plr::jobs::encode_request(1, {"k", key, {}});
    auto d = plr::jobs::decode_message(m.data(), m.size(), "test");
    ASSERT_FALSE(d) << key;
    EXPECT_NE(d.error().message.find("key"), std::string::npos) << d.error().message;
  }
}

TEST(JobMessages, RefuseGarbageAndCutShortMessages) {
  const Bytes m = plr::jobs::encode_request(1, {"kind", "key", Bytes(100, 7)});
  for (std::size_t n = 0; n < m.size(); n += 7)
    EXPECT_FALSE(plr::jobs::decode_message(m.data(), n, "test")) << n;
  Bytes garbage(64, 0xab);
  EXPECT_FALSE(plr::jobs::decode_message(garbage.data(), garbage.size(), "test"));
}

}  // namespace
