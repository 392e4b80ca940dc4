// The kernel's message buffer: allocation, copies, wrapped and loaned bytes,
// reference counts, and the count of live buffers the leak checks rely on.
#include "message.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <memory>

namespace plr::kernel {
namespace {

class MessageTest : public ::testing::Test {
 protected:
  void TearDown() override { EXPECT_EQ(live_messages(), baseline_) << "a buffer leaked"; }
  const std::int64_t baseline_ = live_messages();
};

TEST_F(MessageTest, AllocatedBuffersAreCountedUntilTheLastReferenceGoes) {
  std::uint8_t* data = nullptr;
  plr_msg* m = msg_alloc(64, &data);
  ASSERT_NE(data, nullptr);
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(data) % 8, 0u) << "FlatBuffers needs 8-byte alignment";
  EXPECT_EQ(live_messages(), baseline_ + 1);
  msg_retain(m);
  msg_release(m);
  EXPECT_EQ(live_messages(), baseline_ + 1) << "one reference is left";
  msg_release(m);
}

TEST_F(MessageTest, AZeroSizeBufferStillHasStorage) {
  std::uint8_t* data = nullptr;
  plr_msg* m = msg_alloc(0, &data);
  EXPECT_NE(data, nullptr);
  EXPECT_EQ(msg_view(m).size, 0u);
  msg_release(m);
}

TEST_F(MessageTest, ACopyOwnsItsBytesAndKeepsTheirType) {
  const std::uint8_t bytes[] = {1, 2, 3, 4, 5};
  plr_msg* m = msg_copy(bytes, sizeof bytes, 42, 3, 1234);
  const plr_msg_view v = msg_view(m);
  ASSERT_EQ(v.size, sizeof bytes);
  EXPECT_NE(v.data, bytes);
  EXPECT_EQ(std::memcmp(v.data, bytes, sizeof bytes), 0);
  EXPECT_EQ(v.type_id, 42u);
  EXPECT_EQ(v.schema_version, 3u);
  EXPECT_EQ(v.stamp_ns, 1234);
  msg_release(m);
}

TEST_F(MessageTest, TheViewIsTheFilledRange) {
  std::uint8_t* data = nullptr;
  plr_msg* m = msg_alloc(16, &data);
  m->offset = 4;
  m->size = 8;
  EXPECT_EQ(msg_view(m).data, data + 4);
  EXPECT_EQ(msg_view(m).size, 8u);
  msg_release(m);
}

TEST_F(MessageTest, AWrappedBufferKeepsItsOwnerAliveAndIsReadInPlace) {
  auto owner = std::make_shared<std::vector<std::uint8_t>>(std::vector<std::uint8_t>{9, 8, 7});
  std::weak_ptr<std::vector<std::uint8_t>> watch = owner;
  const int origin = 0;
  plr_msg* m = msg_wrap(owner->data(), owner->size(), 7, 1, owner, &origin);
  const auto* bytes = owner->data();
  owner.reset();
  EXPECT_FALSE(watch.expired()) << "the message keeps its bytes alive";
  EXPECT_EQ(msg_view(m).data, bytes) << "zero copy";
  EXPECT_EQ(m->origin, &origin);
  msg_release(m);
  EXPECT_TRUE(watch.expired());
}

TEST_F(MessageTest, ALoanedBufferDropsItsLoanWithTheLastReference) {
  struct Loan final : MsgLoan {
    explicit Loan(bool* gone) : gone(gone) {}
    ~Loan() override { *gone = true; }
    bool commit(const plr_msg&) override { return true; }
    bool* gone;
  };
  bool gone = false;
  std::uint8_t slot[32] = {};
  plr_msg* m = msg_loaned(slot, sizeof slot, std::make_unique<Loan>(&gone));
  EXPECT_EQ(msg_view(m).data, slot);
  msg_retain(m);
  msg_release(m);
  EXPECT_FALSE(gone);
  msg_release(m);
  EXPECT_TRUE(gone);
}

TEST_F(MessageTest, MsgRefHoldsOneReference) {
  std::uint8_t* data = nullptr;
  MsgRef a(msg_alloc(8, &data));
  {
    MsgRef b = a;  // a second reference
    MsgRef c = std::move(b);
    EXPECT_EQ(b.msg, nullptr);
    EXPECT_EQ(c.msg, a.msg);
    EXPECT_EQ(c.msg->refs.load(), 2u);
  }
  EXPECT_EQ(a.msg->refs.load(), 1u);
}

}  // namespace
}  // namespace plr::kernel
