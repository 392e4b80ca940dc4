// A loan: a message built straight into a kernel buffer and published without
// a copy; one that outgrows its buffer is copied once; one dropped goes back.
#include <plr/context.hpp>
#include <plr/messages.hpp>
#include <plr/testing/fake_kernel.hpp>

#include <gtest/gtest.h>

namespace plr {
namespace {

class LoanTest : public ::testing::Test {
 protected:
  void SetUp() override {
    auto p = ctx_.advertise<msg::Count>("count");
    ASSERT_TRUE(p) << p.error().message;
    pub_ = *p;
  }
  void TearDown() override { EXPECT_EQ(k_.live_messages(), 0) << "a buffer leaked"; }
  std::int64_t published_value() const {
    const auto s = k_.published("count");
    return s.empty() || s.back().as<msg::Count>() == nullptr ? -1
                                                             : s.back().as<msg::Count>()->value();
  }

  testing::FakeKernel k_;
  Context ctx_{k_.test_api()};
  Publisher<msg::Count> pub_;
};

TEST_F(LoanTest, AMessageBuiltInTheLoanIsPublishedInPlace) {
  auto loan = pub_.loan(256);
  ASSERT_TRUE(loan) << loan.error().message;
  auto& fbb = loan->builder();
  fbb.Finish(msg::CreateCount(fbb, 7));
  const auto* built = fbb.GetBufferPointer();
  EXPECT_TRUE(built >= loan->data() && built < loan->data() + loan->capacity())
      << "built inside the loaned buffer";
  ASSERT_TRUE(loan->publish());
  EXPECT_EQ(published_value(), 7);
}

TEST_F(LoanTest, AMessageThatOutgrowsItsLoanIsCopiedOnce) {
  auto loan = pub_.loan(8);
  ASSERT_TRUE(loan);
  auto& fbb = loan->builder();
  fbb.Finish(msg::CreateCount(fbb, 1234567));
  ASSERT_TRUE(loan->publish());
  EXPECT_EQ(published_value(), 1234567);
}

TEST_F(LoanTest, BytesWrittenByHandArePublishedAsTheyAre) {
  flatbuffers::FlatBufferBuilder fbb;
  fbb.Finish(msg::CreateCount(fbb, 3));
  auto loan = pub_.loan(fbb.GetSize() + 16);
  ASSERT_TRUE(loan);
  std::memcpy(loan->data() + 16, fbb.GetBufferPointer(), fbb.GetSize());
  ASSERT_TRUE(loan->publish(16, fbb.GetSize()));
  EXPECT_EQ(published_value(), 3);
}

TEST_F(LoanTest, ALoanIsPublishedOnce) {
  auto loan = pub_.loan(64);
  ASSERT_TRUE(loan);
  const Status empty = loan->publish();
  ASSERT_FALSE(empty);
  EXPECT_EQ(empty.error().message, "publish: nothing built in the loan");
  auto& fbb = loan->builder();
  fbb.Finish(msg::CreateCount(fbb, 1));
  ASSERT_TRUE(loan->publish());
  const Status twice = loan->publish();
  ASSERT_FALSE(twice);
  EXPECT_EQ(twice.error().code, PLR_ERR_STATE);
}

TEST_F(LoanTest, ADroppedLoanGoesBackUnpublished) {
  {
    auto loan = pub_.loan(64);
    ASSERT_TRUE(loan);
    auto& fbb = loan->builder();
    fbb.Finish(msg::CreateCount(fbb, 1));
  }
  EXPECT_TRUE(k_.published("count").empty());
}

TEST_F(LoanTest, AnUnknownPublisherGetsNoLoan) {
  const Publisher<msg::Count> stray(k_.test_api(), 987654);
  const auto loan = stray.loan(64);
  ASSERT_FALSE(loan);
  EXPECT_EQ(loan.error().code, PLR_ERR_UNAVAILABLE);
}

}  // namespace
}  // namespace plr
