// plr_planner_conformance <plugin.so> [<params json>] [gtest flags]
#include <gtest/gtest.h>

#include <plr/testing/conformance.hpp>

#include "plr/planning/testing/planner_conformance.hpp"

int main(int argc, char** argv) {
  return plr::testing::conformance_main(
      argc, argv, "The planner conformance suite on one planner plug-in",
      [](const std::string& plugin, const std::string& params) {
        plr::planning::testing::register_planner_conformance_tests(plugin, params);
        return RUN_ALL_TESTS();
      });
}
