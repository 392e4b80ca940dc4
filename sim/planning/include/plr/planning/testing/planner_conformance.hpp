// The planner conformance suite: what every planner plug-in must do behind
// the `plan` service, checked through a FakeKernel the way a caller sees it.
// It runs after the SDK's own conformance suite (life cycle, leaks,
// parameters) on hand-made worlds:
//
// - each mode the planner declares reaches its goal: joint goals exactly,
//   pose goals within tolerance, M4 on its line, M5 in one straight move;
// - every trajectory starts at the start, stays within joint limits and is
//   free of collisions, re-checked densely with FCL against the boxes and the
//   trailer's walls (not with the planner's own checker);
// - a goal in collision is GoalInvalid naming what it hits; malformed
//   requests are InvalidRequest with a one-line reason naming the field;
// - a start in light contact is left with the M6 escape, then planned from;
// - with an expansion budget the same request gives the same trajectory,
//   and a budget too small says so.
//
// Modes a planner does not declare are answered InvalidRequest ("... is not
// a mode of planner ..."); their checks are skipped, but M1 is required.
//
// From CMake: plr_add_planner_conformance_test(<plugin target> [PARAMS <json>]).
// By hand: plr_planner_conformance <plugin.so> [<params json>] [gtest flags].
#pragma once

#include <string>

namespace plr::planning::testing {

// Registers the SDK's conformance tests and the planner checks (suite
// "PlannerConformance"); call after ::testing::InitGoogleTest.
void register_planner_conformance_tests(const std::string& plugin_path,
                                        const std::string& params_json = "{}");

}  // namespace plr::planning::testing
