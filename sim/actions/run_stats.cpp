#include "plr/actions/run_stats.hpp"

#include <algorithm>
#include <cmath>

#include "plr/planning/plan_query.hpp"

namespace plr::actions {

void Accumulator::add(double x) {
  ++n;
  sum += x;
  const double d = x - mean;
  mean += d / static_cast<double>(n);
  m2 += d * (x - mean);
}

double Accumulator::sd() const {
  return n > 1 ? std::sqrt(m2 / static_cast<double>(n - 1)) : 0.0;
}

void PlannerStats::add(const std::vector<QueryRecord>& queries) {
  using planning::PlanMode;
  for (const auto& q : queries) {
    auto& ms = modes[static_cast<std::size_t>(q.mode)];
    ++ms.queries;
    if (!q.answered) {
      ++ms.failures;
      ++unanswered;
      continue;
    }
    if (q.status != planning::PlanStatus::kSolved) ++ms.failures;
    ms.ms.add(q.planning_ms);
    ms.expansions.add(static_cast<double>(q.expansions));
    ms.max_expansions = std::max(ms.max_expansions, q.expansions);
    ++planners[q.planner.empty() ? "?" : q.planner];
    if (q.escaped && q.mode != PlanMode::kEscape) {
      // The escape the planner ran first counts as an M6 query of its own.
      ++m6_implicit;
      auto& m6 = modes[static_cast<std::size_t>(PlanMode::kEscape)];
      ++m6.queries;
      if (q.escape_ms > 0) m6.ms.add(q.escape_ms);
    }
  }
}

void add_execution(ActionStats& pick, ActionStats& sweep, sim::Action action,
                   const Outcome& outcome) {
  auto& as = sim::kind(action) == sim::ActionKind::kPick ? pick : sweep;
  ++as.executions;
  as.boxes += outcome.boxes;
  ++as.boxes_histogram[outcome.boxes];
  as.plan_s.add(outcome.plan_model_s);
  as.exec_s.add(outcome.exec_s);
}

double boxes_per_execution(const ActionStats& a) {
  return a.executions ? static_cast<double>(a.boxes) / static_cast<double>(a.executions) : 0.0;
}

double boxes_per_success(const ActionStats& a) {
  const auto none = a.boxes_histogram.count(0) ? a.boxes_histogram.at(0) : 0;
  const auto n = a.executions - std::min(a.executions, none);
  return n ? static_cast<double>(a.boxes) / static_cast<double>(n) : 0.0;
}

int plan_mode_dof(int mode) {
  const auto m = static_cast<planning::PlanMode>(mode);
  if (m == planning::PlanMode::kArmCartesian) return 1;
  return static_cast<int>(planning::planned_joints(m).size());
}

nlohmann::json modes_json(const PlannerStats& s) {
  nlohmann::json modes = nlohmann::json::object();
  static constexpr std::array<const char*, 7> kNames = {
      "", "M1 arm", "M2 arm+base", "M3 nose", "M4 arm line", "M5 base line", "M6 escape"};
  for (int m = 1; m <= 6; ++m) {
    const auto& ms = s.modes[static_cast<std::size_t>(m)];
    modes["M" + std::to_string(m)] = {
        {"name", kNames[static_cast<std::size_t>(m)]},
        {"dof", plan_mode_dof(m)},
        {"queries", ms.queries},
        {"failures", ms.failures},
        {"failure_rate", ms.queries ? static_cast<double>(ms.failures) / ms.queries : 0.0},
        {"mean_ms", ms.ms.mean},
        {"sd_ms", ms.ms.sd()},
        {"ms_samples", ms.ms.n},
        {"mean_expansions", ms.expansions.mean},
        {"max_expansions", ms.max_expansions}};
  }
  modes["M6"]["implicit"] = s.m6_implicit;
  return modes;
}

nlohmann::json action_json(const ActionStats& a) {
  const double total = a.plan_s.sum + a.exec_s.sum;
  nlohmann::json histogram = nlohmann::json::object();
  for (const auto& [boxes, n] : a.boxes_histogram) histogram[std::to_string(boxes)] = n;
  return {{"executions", a.executions},
          {"boxes", a.boxes},
          {"boxes_per_execution", boxes_per_execution(a)},
          {"boxes_per_success", boxes_per_success(a)},
          {"boxes_histogram", histogram},
          {"plan_s", a.plan_s.mean},
          {"plan_s_sd", a.plan_s.sd()},
          {"exec_s", a.exec_s.mean},
          {"exec_s_sd", a.exec_s.sd()},
          {"boxes_per_s", total > 0 ? static_cast<double>(a.boxes) / total : 0.0}};
}

std::optional<double> robot_time_to_share(const nlohmann::json& curve, double total, double share) {
  const double goal = share * total;
  if (!(goal > 0) || !curve.is_array()) return std::nullopt;
  for (const auto& p : curve)
    if (p.is_array() && p.size() == 2 && p[0].is_number() && p[1].is_number() &&
        p[1].get<double>() >= goal - 1e-9)
      return p[0].get<double>();
  return std::nullopt;
}

}  // namespace plr::actions
