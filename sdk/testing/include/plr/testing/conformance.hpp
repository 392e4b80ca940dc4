// The conformance suite every plug-in passes: a GoogleTest harness that loads
// the plug-in's library into a FakeKernel and checks its descriptor, its life
// cycle (order, repetition, refusals, idempotent deactivate), that it leaks
// nothing, that it refuses parameters it does not know, and that it declares
// (PLR_INTERFACE) every topic and service it offers.
//
// From CMake, use plr_add_conformance_test(<plugin target> [PARAMS <json>]).
// By hand: plr_conformance <plugin.so> [<params json>] [gtest flags].
#pragma once

#include <functional>
#include <string>

namespace plr::testing {

struct ConformanceOptions {
  std::string plugin_path;
  // Parameters a valid configuration needs (a JSON object); the suite adds an
  // unknown key to them to check the refusal.
  std::string params_json = "{}";
};

// The key the suite adds to check that unknown parameters are refused.
inline constexpr const char* kUnknownParam = "definitely_not_a_param";

// Registers one test per check, in the suite "Conformance". Call after
// ::testing::InitGoogleTest and before RUN_ALL_TESTS.
void register_conformance_tests(const ConformanceOptions& options);

// Registers the tests and runs every registered test; returns RUN_ALL_TESTS().
// ::testing::InitGoogleTest must have run.
int run_conformance(const std::string& plugin_path, const std::string& params_json = "{}");

// The command line of a conformance runner: PLUGIN.so [PARAMS_JSON] and
// GoogleTest's --gtest_* flags, with --help. Initialises GoogleTest and
// returns run(plugin, params), or 0 after --help, or 2 after a one-line error.
int conformance_main(
    int argc, char** argv, const std::string& description,
    const std::function<int(const std::string& plugin_path, const std::string& params_json)>& run);

}  // namespace plr::testing
