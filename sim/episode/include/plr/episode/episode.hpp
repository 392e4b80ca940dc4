// What an unloading run did: its figures, its steps and its curve, as the
// engine (plr/episode/engine.hpp) records them after each action.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "plr/actions/action_model.hpp"
#include "plr/actions/run_stats.hpp"
#include "plr/episode/curve.hpp"
#include "plr/episode/left.hpp"

namespace plr::episode {

struct EpisodeStep {
  std::string source;  // where the action's strategy came from (StrategyChoice)
  sim::Action action{};
  sim::Observation observation{};
  // The raw figures the observation was classified from (SceneAnalysis).
  double wall_height = 0, pile_height = 0, pile_depth = 0;
  actions::Outcome outcome;
  std::vector<std::string> notes;  // the action's log lines (Reporter::note)
};

struct Episode {
  std::uint32_t boxes_total = 0;  // in the trailer at the first observation
  // Since the first observation: the world's count, and during an action the
  // count at its start.
  std::uint32_t boxes_unloaded = 0;
  double robot_time_s = 0.0;  // execution + modelled planning (deterministic)
  double plan_wall_s = 0.0;   // what planning took on this machine
  // Robot time that bought nothing: all of each action that unloaded no box,
  // and the planning the robot waited for in the others (issue 46).
  double wasted_s = 0.0;
  double sim_time_s = 0.0;  // the simulator's clock at the last action's end
  std::uint64_t actions = 0;
  std::uint64_t not_applicable = 0;  // actions with nothing to do in their region
  std::uint64_t robot_trailer_contacts = 0;
  std::uint64_t failed_grasps = 0;
  std::uint64_t strategies_asked = 0;
  std::uint64_t strategy_steps = 0;  // actions taken by following a branch
  std::uint64_t recoveries = 0;      // losses of the world survived (Recovery)
  actions::PlannerStats planner;     // the paper's Table I
  actions::ActionStats pick, sweep;  // its Table II
  Curve curve;
  std::vector<EpisodeStep> steps;
  std::string stop_reason;  // empty until the run ends by its rules
  std::vector<LeftBox> left;
  sim::World final_world;  // as perceived at the end
};

// wasted_s as a share of robot_time_s (0 before any robot time).
inline double wasted_share(const Episode& e) {
  return e.robot_time_s > 0 ? e.wasted_s / e.robot_time_s : 0.0;
}

}  // namespace plr::episode
