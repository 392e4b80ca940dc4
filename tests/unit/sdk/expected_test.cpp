#include <plr/expected.hpp>

#include <gtest/gtest.h>

#include <cstdint>
#include <memory>
#include <string>

namespace {

TEST(Expected, HoldsAValue) {
  plr::Expected<int> e = 42;
  ASSERT_TRUE(e);
  EXPECT_TRUE(e.has_value());
  EXPECT_EQ(e.value(), 42);
  EXPECT_EQ(*e, 42);
}

TEST(Expected, HoldsAnErrorWithCodeAndText) {
  plr::Expected<int> e = plr::make_error(PLR_ERR_TIMEOUT, "plan: timed out after 5 s");
  ASSERT_FALSE(e);
  EXPECT_EQ(e.error().code, PLR_ERR_TIMEOUT);
  EXPECT_EQ(e.error().message, "plan: timed out after 5 s");
}

TEST(Expected, MovesMoveOnlyValuesOut) {
  plr::Expected<std::unique_ptr<std::string>> e = std::make_unique<std::string>("payload");
  ASSERT_TRUE(e);
  EXPECT_EQ(e->get()->size(), 7u);
  std::unique_ptr<std::string> out = std::move(e).value();
  EXPECT_EQ(*out, "payload");
}

TEST(Expected, ConvertsWhatTheValueTypeAccepts) {
  plr::Expected<std::unique_ptr<const std::string>> e = std::make_unique<std::string>("derived");
  ASSERT_TRUE(e);
  EXPECT_EQ(**e, "derived");
  plr::Expected<std::string> text = "literal";
  EXPECT_EQ(*text, "literal");
}

// Reading the wrong alternative is a bug in the caller: it aborts, naming it.
TEST(ExpectedDeathTest, ValueOfAnErrorAbortsWithTheError) {
  plr::Expected<int> e = plr::make_error(PLR_ERR_INVALID, "bad input");
  EXPECT_DEATH((void)e.value(), "value\\(\\) of an error \\(the error: bad input\\)");
}

TEST(ExpectedDeathTest, ErrorOfAValueAborts) {
  const plr::Expected<int> e = 1;
  EXPECT_DEATH((void)e.error(), "error\\(\\) of a value");
  const plr::Status ok;
  EXPECT_DEATH((void)ok.error(), "error\\(\\) of a success");
}

// The data-path form: an enum error, no heap, same interface.
enum class RingError : std::uint8_t { kFull, kClosed };

plr::Expected<std::uint32_t, RingError> take(bool full) {
  if (full) return RingError::kFull;
  return 7u;
}

TEST(Expected, HoldsAnEnumErrorWithoutAString) {
  static_assert(sizeof(plr::Expected<std::uint32_t, RingError>) <= 8);
  static_assert(sizeof(plr::Expected<void, RingError>) <= 2);
  EXPECT_EQ(take(false).value(), 7u);
  ASSERT_FALSE(take(true));
  EXPECT_EQ(take(true).error(), RingError::kFull);
  plr::Expected<void, RingError> done;
  EXPECT_TRUE(done);
  plr::Expected<void, RingError> closed = RingError::kClosed;
  ASSERT_FALSE(closed);
  EXPECT_EQ(closed.error(), RingError::kClosed);
}

TEST(ExpectedDeathTest, ValueOfAnEnumErrorAborts) {
  EXPECT_DEATH((void)take(true).value(), "value\\(\\) of an error");
}

TEST(Status, DefaultIsSuccess) {
  plr::Status s;
  EXPECT_TRUE(s);
  EXPECT_TRUE(s.has_value());
}

TEST(Status, CarriesTheError) {
  plr::Status s =
      plr::make_error(PLR_ERR_STATE, "activate: node is unconfigured, needs configured");
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().code, PLR_ERR_STATE);
  EXPECT_EQ(s.error().message, "activate: node is unconfigured, needs configured");
}

}  // namespace
