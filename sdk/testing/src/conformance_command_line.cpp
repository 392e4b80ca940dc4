#include <plr/testing/conformance.hpp>

#include <gtest/gtest.h>
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <cstdio>

namespace plr::testing {

int conformance_main(
    int argc, char** argv, const std::string& description,
    const std::function<int(const std::string& plugin_path, const std::string& params_json)>& run) {
  CLI::App app{description};
  // GoogleTest's flags are left to it.
  app.allow_extras();
  app.footer("GoogleTest's flags (--gtest_filter=..., --gtest_list_tests, ...) are passed on.");
  std::string plugin, params = "{}";
  app.add_option("plugin", plugin, "The plug-in's shared library")->required();
  app.add_option("params", params, "Parameters a valid configuration needs (a JSON object)")
      ->capture_default_str()
      ->check([](const std::string& p) {
        return nlohmann::json::parse(p, nullptr, false).is_object()
                   ? std::string()
                   : "params must be a JSON object: " + p;
      });
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  for (const std::string& extra : app.remaining()) {
    if (extra.rfind("--gtest_", 0) != 0) {
      std::fprintf(stderr, "%s: unexpected argument '%s' (--help lists the arguments)\n",
                   app.get_name().c_str(), extra.c_str());
      return 2;
    }
  }
  ::testing::InitGoogleTest(&argc, argv);
  return run(plugin, params);
}

}  // namespace plr::testing
