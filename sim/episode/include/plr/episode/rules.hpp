// An unloading run's stop rules, the same online (the executor plug-in, over
// the bus) and offline (in process): which actions are left out until
// progress, and when the run ends.
#pragma once

#include <cstdint>
#include <optional>
#include <set>
#include <string>

#include "plr/actions/action_model.hpp"

namespace plr::episode {

struct RunLimits {
  std::uint64_t max_actions = 0;  // 0: no limit
  // Actions in a row that move no box, whatever the exclusions say (a pick
  // whose grip keeps failing is retried until the box is given up).
  std::uint64_t max_idle_actions = 24;
  // Robot seconds (execution + modelled planning): the run ends once this
  // much has passed; 0: no limit.
  double max_robot_time_s = 0.0;
};

// The run goes on while some action may still move a box. An action that
// moved nothing is not tried again before progress, unless its grip failed:
// the grip memory then makes the next attempt differ (more cups, a slower
// carry) and gives the box up in the end. When every action has been
// tried and some moved boxes without unloading any, the scene is no longer
// the one the first were tried on: all are tried once more (at most
// kExtraRounds times before progress), each round with its own
// max_idle_actions.
class RunRules {
 public:
  explicit RunRules(RunLimits limits = {}) : limits_(limits) {}

  // Why the run ends before its next action, with `boxes` in the trailer.
  std::optional<std::string> stop(std::size_t boxes) const;
  void record(sim::Action action, const actions::Outcome& outcome);

  bool excluded(sim::Action action) const;
  // Nothing excluded: the strategy's own next step may be followed.
  bool fresh() const { return excluded_.empty(); }
  const std::set<std::uint8_t>& exclusions() const { return excluded_; }
  std::uint64_t actions() const { return actions_; }

 private:
  static constexpr int kExtraRounds = 2;

  RunLimits limits_;
  std::set<std::uint8_t> excluded_;
  bool shifted_ = false;  // an action of this round moved boxes
  int rounds_ = 0;        // extra rounds since the last progress
  std::uint64_t actions_ = 0, idle_ = 0;
  double robot_time_s_ = 0.0;
};

}  // namespace plr::episode
