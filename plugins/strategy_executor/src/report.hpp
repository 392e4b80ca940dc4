// What the executor measures (the paper's Tables I and II, the unloading
// curve) and the files it writes at the end of a run.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace plr::executor {

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

struct CurvePoint {
  double robot_time_s = 0;  // execution + modelled planning (deterministic)
  std::uint32_t boxes = 0;
};

// One action of the run: what the robot saw, did, and got.
struct StepRecord {
  std::string action;
  std::string observation;
  double wall_height = 0, pile_height = 0, pile_depth = 0;  // m, the scene's raw figures
  bool applicable = true;
  std::uint32_t boxes = 0;
  double robot_time_s = 0;
};

struct RunStats {
  std::array<ModeStats, 7> modes{};  // index = plan mode 1..6
  std::uint64_t m6_implicit = 0;     // escapes the planner ran inside another query
  // Who answered the plan queries (a hot swap shows as two names), and the
  // queries no planner answered (lost in transit, timed out on the bus).
  std::map<std::string, std::uint64_t> planners;
  std::uint64_t plan_calls_unanswered = 0;
  ActionStats pick, sweep;
  std::vector<CurvePoint> curve;
  std::vector<StepRecord> steps;
  std::uint32_t boxes_total = 0;
  std::uint32_t boxes_unloaded = 0;
  double sim_time_s = 0;
  double robot_time_s = 0;  // execution + modelled planning (deterministic)
  double plan_wall_s = 0;   // what planning took on this machine
  double wall_time_s = 0;
  std::uint64_t robot_trailer_collisions = 0;
  std::uint64_t failed_grasps = 0;
  std::uint64_t not_applicable = 0;    // actions with nothing to do in their region
  std::uint64_t recoveries = 0;        // simulator restarts survived
  std::uint64_t strategies_asked = 0;  // strategy/next calls
  std::uint64_t strategy_steps = 0;    // actions taken by following a branch
  std::string stop_reason;
  // Each box left in the trailer: why (a category) and what stood in its way.
  struct LeftBox {
    std::uint32_t id = 0;
    std::string reason, detail;
  };
  std::vector<LeftBox> boxes_left;
};

nlohmann::json to_json(const RunStats& stats);

// The unloading curve: boxes unloaded against robot time.
std::string curve_svg(const std::vector<CurvePoint>& curve, std::uint32_t total,
                      const std::string& title);

// One progress line: "[#####-----] 12/30 boxes  40%  0.21 boxes/s  Pick(high, left): approach".
std::string progress_line(std::uint32_t done, std::uint32_t total, double robot_time_s,
                          const std::string& what, int width = 24);

}  // namespace plr::executor
