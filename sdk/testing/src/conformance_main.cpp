// plr_conformance <plugin.so> [<params json>] [gtest flags]
#include <plr/testing/conformance.hpp>

int main(int argc, char** argv) {
  return plr::testing::conformance_main(
      argc, argv, "The conformance suite every PLR plug-in passes, on one plug-in",
      [](const std::string& plugin, const std::string& params) {
        return plr::testing::run_conformance(plugin, params);
      });
}
