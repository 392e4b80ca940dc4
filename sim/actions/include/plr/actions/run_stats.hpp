// What a run's actions measure, the same online (the executor's report.json)
// and offline (the evaluation): the planner's queries per mode (the paper's
// Table I) and the picks' and sweeps' times and boxes (its Table II).
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "plr/actions/action_model.hpp"

namespace plr::actions {

// Running mean and spread (Welford), so no sample list is kept.
struct Accumulator {
  std::uint64_t n = 0;
  double mean = 0, m2 = 0, sum = 0;
  void add(double x);
  double sd() const;
};

struct ModeStats {
  std::uint64_t queries = 0;
  std::uint64_t failures = 0;
  Accumulator ms;  // planning time of the queries that reported one
  Accumulator expansions;
  std::uint64_t max_expansions = 0;
};

struct ActionStats {
  std::uint64_t executions = 0;
  std::uint64_t boxes = 0;
  // Executions by the boxes each moved out (0, 1, 2, ...): a multi-box pick
  // shows as 2 or more.
  std::map<std::uint32_t, std::uint64_t> boxes_histogram;
  Accumulator plan_s;  // per execution: planning time the robot waited for (modelled)
  Accumulator exec_s;  // per execution: simulated execution time
};

struct PlannerStats {
  std::array<ModeStats, 7> modes{};  // index = plan mode 1..6
  std::uint64_t m6_implicit = 0;     // escapes the planner ran inside another query
  // Who answered the plan queries (a hot swap shows as two names), and the
  // queries no planner answered (lost in transit, timed out on the bus).
  std::map<std::string, std::uint64_t> planners;
  std::uint64_t unanswered = 0;

  void add(const std::vector<QueryRecord>& queries);
};

// Counts an applicable action's execution (a pick or a sweep, by `action`).
void add_execution(ActionStats& pick, ActionStats& sweep, sim::Action action,
                   const Outcome& outcome);

// {"M1": {name, dof, queries, failures, failure_rate, mean_ms, sd_ms,
// ms_samples, mean_expansions, max_expansions}, ..., "M6": {..., implicit}}
nlohmann::json modes_json(const PlannerStats& stats);
// {executions, boxes, boxes_per_execution, boxes_per_success, boxes_histogram,
// plan_s, plan_s_sd, exec_s, exec_s_sd, boxes_per_s}
nlohmann::json action_json(const ActionStats& stats);
// Boxes per execution, and per execution that moved any.
double boxes_per_execution(const ActionStats& stats);
double boxes_per_success(const ActionStats& stats);
// The degrees of freedom a mode plans (M4: its one progress variable).
int plan_mode_dof(int mode);

// The robot time at which a curve ([[robot s, boxes], ...], as report.json
// has it) reached `share` of `total` boxes; none if it never did. Issue 21
// compares PLR with H by the time to 90 %.
std::optional<double> robot_time_to_share(const nlohmann::json& curve, double total, double share);

}  // namespace plr::actions
