// plr_planner_conformance <plugin.so> [<params json>] [gtest flags]
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstdio>

#include "plr/planning/testing/planner_conformance.hpp"

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);  // removes the gtest flags it knows
  if (argc < 2 || argc > 3) {
    std::fprintf(stderr, "usage: %s <plugin.so> [<params json>] [gtest flags]\n", argv[0]);
    return 2;
  }
  const std::string params = argc == 3 ? argv[2] : "{}";
  if (!nlohmann::json::parse(params, nullptr, false).is_object()) {
    std::fprintf(stderr, "%s: params must be a JSON object: %s\n", argv[0], params.c_str());
    return 2;
  }
  plr::planning::testing::register_planner_conformance_tests(argv[1], params);
  return RUN_ALL_TESTS();
}
