#include <plr/params.hpp>

#include <gtest/gtest.h>

#include <string>

namespace {

using plr::ParamError;
using plr::Params;

// The message a ParamError carries, or "" when none was thrown.
template <class F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const ParamError& e) {
    return e.what();
  }
  return "";
}

const Params kParams(nlohmann::json::parse(
    R"({"rate": 2.5, "count": 3, "negative": -1, "name": "arm", "on": true, "list": [1, 2]})"));

TEST(Params, ReadsTypedValues) {
  EXPECT_DOUBLE_EQ(kParams.require<double>("rate"), 2.5);
  EXPECT_EQ(kParams.require<int>("count"), 3);
  EXPECT_EQ(kParams.require<unsigned>("count"), 3u);
  EXPECT_EQ(kParams.require<std::string>("name"), "arm");
  EXPECT_TRUE(kParams.require<bool>("on"));
}

TEST(Params, FallsBackOnlyWhenMissing) {
  EXPECT_EQ(kParams.get<int>("absent", 7), 7);
  EXPECT_EQ(kParams.get<int>("count", 7), 3);
  EXPECT_FALSE(kParams.has("absent"));
  EXPECT_TRUE(kParams.has("count"));
}

TEST(Params, MissingRequiredKeyIsNamed) {
  EXPECT_EQ(error_of([] { (void)kParams.require<int>("limit"); }),
            "param 'limit': required but missing");
}

TEST(Params, WrongTypesAreNamedWithTheValue) {
  EXPECT_EQ(error_of([] { (void)kParams.require<int>("name"); }),
            "param 'name': expected a number, got \"arm\"");
  EXPECT_EQ(error_of([] { (void)kParams.require<std::string>("count"); }),
            "param 'count': expected a string, got 3");
  EXPECT_EQ(error_of([] { (void)kParams.require<bool>("count"); }),
            "param 'count': expected a boolean, got 3");
  EXPECT_EQ(error_of([] { (void)kParams.get<double>("list", 0.0); }),
            "param 'list': expected a number, got [1,2]");
}

TEST(Params, NegativeForUnsignedIsRefused) {
  EXPECT_EQ(error_of([] { (void)kParams.require<unsigned>("negative"); }),
            "param 'negative': expected a non-negative number, got -1");
}

TEST(Params, UnknownKeysAreRefusedByName) {
  EXPECT_EQ(error_of([] {
              kParams.allow_only({"rate", "count", "negative", "name", "on"});
            }),
            "param 'list': unknown parameter");
  EXPECT_EQ(error_of([] {
              kParams.allow_only({"rate", "count", "negative", "name", "on", "list"});
            }),
            "");
}

TEST(Params, EmptyAllowsNothingAndNeedsNothing) {
  Params empty;
  EXPECT_EQ(error_of([&] { empty.allow_only({}); }), "");
  EXPECT_TRUE(empty.json().is_object());
}

}  // namespace
