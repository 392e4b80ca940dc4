// A small synthetic evaluation the summary and report tests share: two
// environments, H and PLR, a handful of run results (as run_one writes
// them) whose figures can be worked out by hand.
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "plr/evaluation/settings.hpp"

namespace plr::evaluation::testing {

// Horizon 120 s: the grid is every second.
inline EvaluationSettings settings() {
  EvaluationSettings s;
  s.environments = {{"A1", sim::EnvFamily::kA1, true, {}}, {"B1", sim::EnvFamily::kB1, false, {}}};
  s.methods = {Method::kHardcoded, Method::kPlr};
  s.max_robot_time_s = 120;
  s.seeds = 10;
  s.quick_seeds = 3;
  s.library = "lib";
  s.model = "model.json";
  return s;
}

inline nlohmann::json run(const std::string& env, const std::string& method, int seed,
                          nlohmann::json curve) {
  return {{"environment", env},
          {"method", method},
          {"seed", seed},
          {"world", env + "-" + std::to_string(seed)},
          {"boxes_total", 10},
          {"boxes_unloaded", curve.back()[1]},
          {"robot_time_s", curve.back()[0]},
          {"actions", 4},
          {"library_actions", method == "PLR" ? 2 : 0},
          {"stop_reason", "trailer empty"},
          {"wall_s", 30.0},
          {"curve", std::move(curve)}};
}

// On A1, H: 10, 6 and 10 boxes by the horizon (90 % at 60 s and 40 s, one
// never; H's actions 3 boxes in 10 s); PLR: 12 and 12. One H run failed.
// On B1, PLR alone.
inline std::vector<nlohmann::json> runs() {
  std::vector<nlohmann::json> out;
  out.push_back(run("A1", "H", 1, {{0, 0}, {60, 10}}));
  out.back()["steps"] = {{{"source", "hardcoded"}, {"boxes", 3}, {"robot_time_s", 10.0}}};
  out.push_back(run("A1", "H", 2, {{0, 0}, {30, 4}, {60, 6}}));
  out.push_back(run("A1", "H", 3, {{0, 0}, {40, 10}}));
  out.push_back({{"environment", "A1"}, {"method", "H"}, {"seed", 4}, {"error", "timed out"}});
  nlohmann::json a = run("A1", "PLR", 1, {{0, 0}, {50, 12}});
  nlohmann::json b = run("A1", "PLR", 2, {{0, 0}, {100, 12}});
  // Table I, mode M2: 10 queries (2 failed; 8 answered in 5 ± 1 ms) and 20
  // (all answered in 2 ms).
  a["planner_modes"]["M2"] = {{"name", "arm"},   {"queries", 10},  {"failures", 2},
                              {"ms_samples", 8}, {"mean_ms", 5.0}, {"sd_ms", 1.0}};
  b["planner_modes"]["M2"] = {{"name", "arm"},    {"queries", 20},  {"failures", 0},
                              {"ms_samples", 20}, {"mean_ms", 2.0}, {"sd_ms", 0.0}};
  // Table II: 4 picks of 1 + 9 s moving 4 boxes in one run, none in the
  // other; one sweep of 1 + 5 s moving 3.
  a["action_stats"]["pick"] = {{"executions", 4},  {"boxes_per_s", 0.1}, {"plan_s", 1.0},
                               {"plan_s_sd", 0.0}, {"exec_s", 9.0},      {"exec_s_sd", 0.0},
                               {"boxes", 4}};
  a["action_stats"]["sweep"] = {{"executions", 1},  {"boxes_per_s", 0.5}, {"plan_s", 1.0},
                                {"plan_s_sd", 0.0}, {"exec_s", 5.0},      {"exec_s_sd", 0.0},
                                {"boxes", 3}};
  // Where PLR's actions came from: a library strategy (2 boxes in 10 s) and
  // H (1 box in 10 s).
  a["steps"] = {{{"source", "library:A1-1"}, {"boxes", 2}, {"robot_time_s", 10.0}},
                {{"source", "hardcoded"}, {"boxes", 1}, {"robot_time_s", 10.0}},
                "edited by hand"};
  out.push_back(a);
  out.push_back(b);
  out.push_back(run("B1", "PLR", 1, {{0, 0}, {10, 3}}));
  return out;
}

}  // namespace plr::evaluation::testing
