// What the executor measures (the paper's Tables I and II, the unloading
// curve) and the files it writes at the end of a run.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "plr/actions/run_stats.hpp"

namespace plr::executor {

using actions::Accumulator;
using actions::ActionStats;
using actions::ModeStats;

struct CurvePoint {
  double robot_time_s = 0;  // execution + modelled planning (deterministic)
  std::uint32_t boxes = 0;
};

// One action of the run: what the robot saw, did, and got.
struct StepRecord {
  std::string source;  // where its strategy came from ("library:A1-1", "hardcoded", ...)
  std::string action;
  std::string observation;
  double wall_height = 0, pile_height = 0, pile_depth = 0;  // m, the scene's raw figures
  bool applicable = true;
  std::uint32_t boxes = 0;
  double robot_time_s = 0;
};

// One trailer of a run that unloads several (the executor's `trailers`):
// what the executor counted, and what the simulator holds at its end.
struct TrailerRecord {
  std::string name;  // "A1 seed 3", or the world file
  std::uint32_t boxes_total = 0;
  std::uint32_t boxes_unloaded = 0;      // as the executor counted them
  std::uint32_t sim_boxes_unloaded = 0;  // as the simulator counted them
  std::uint32_t sim_boxes_left = 0;      // still in the simulator's trailer
  std::uint64_t recoveries = 0;
  std::uint64_t plan_calls_unanswered = 0;
  double wall_time_s = 0;
  std::string stop_reason;
  // The simulator's checkpoint folder right after the trailer's start was
  // written (0 without one on disk): the same trailer's start is the same
  // state, so a long run compares these to see the checkpoint grow.
  std::uint64_t start_checkpoint_bytes = 0;
};

struct RunStats {
  actions::PlannerStats planner;  // the paper's Table I
  ActionStats pick, sweep;
  std::vector<CurvePoint> curve;
  std::vector<StepRecord> steps;
  std::uint32_t boxes_total = 0;
  std::uint32_t boxes_unloaded = 0;
  double sim_time_s = 0;
  double robot_time_s = 0;  // execution + modelled planning (deterministic)
  double plan_wall_s = 0;   // what planning took on this machine
  double wasted_s = 0;      // robot time that bought nothing (episode::Episode::wasted_s)
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
  // The trailers finished so far, when the run unloads several.
  std::vector<TrailerRecord> trailers;
};

nlohmann::json to_json(const RunStats& stats);

// The unloading curve: boxes unloaded against robot time.
std::string curve_svg(const std::vector<CurvePoint>& curve, std::uint32_t total,
                      const std::string& title);

// One progress line: "[#####-----] 12/30 boxes  40%  0.21 boxes/s  Pick(high, left): approach".
std::string progress_line(std::uint32_t done, std::uint32_t total, double robot_time_s,
                          const std::string& what, int width = 24);

}  // namespace plr::executor
