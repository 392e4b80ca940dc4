#include <plr/expected.hpp>

#include <gtest/gtest.h>

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

TEST(Expected, ValueOfAnErrorThrows) {
  plr::Expected<int> e = plr::make_error(PLR_ERR_INVALID, "bad");
  EXPECT_THROW((void)e.value(), std::bad_variant_access);
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
