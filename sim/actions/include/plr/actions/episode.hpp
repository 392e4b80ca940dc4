// An unloading run's rules, the same online (the executor plug-in, over the
// bus) and offline (in process, for benchmarks, generation and evaluation):
// which actions are left out until progress, when the run ends, and why each
// box left in the trailer is left. With them, strategy H run in process.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "plr/actions/action_model.hpp"
#include "plr/expected.hpp"
#include "plr/sim/hardcoded_strategy.hpp"

namespace plr::actions {

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
  void record(sim::Action action, const Outcome& outcome);

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

// Why a box is still in the trailer at the end of a run.
enum class LeftReason {
  kGivenUp,     // grasped and lost again and again
  kUnplanned,   // a pick point exists, but no motion to it was found
  kOnRobot,     // lying on the robot, off the trailer's floor
  kBehind,      // wholly behind the robot's front edge: fallen beside or behind the base
  kNoFace,      // no face the vertical plate can seal on (tilted on an edge)
  kOutOfReach,  // even alone in the trailer, the arm cannot reach a face
  kBlocked,     // pickable alone: other boxes stand in the way
};
const char* to_string(LeftReason reason);

struct LeftBox {
  std::uint32_t id = 0;
  LeftReason reason = LeftReason::kBlocked;
  std::string detail;
};

// The boxes of `world`, each with its reason, from what the run learnt
// (`memory`) and the geometry (each box tried alone with every Pick region).
std::vector<LeftBox> boxes_left(const sim::World& world, const sim::JointVector& q,
                                const Memory& memory, const ActionModel& model);
std::map<std::string, std::uint32_t> count_by_reason(const std::vector<LeftBox>& left);

struct EpisodeStep {
  std::string source;  // where the action's strategy came from (StrategyChoice)
  sim::Action action{};
  sim::Observation observation{};
  // The raw figures the observation was classified from (SceneAnalysis).
  double wall_height = 0, pile_height = 0, pile_depth = 0;
  Outcome outcome;
  std::vector<std::string> notes;  // the action's log lines (Reporter::note)
};

struct Episode {
  std::uint32_t boxes_total = 0;
  std::uint32_t boxes_unloaded = 0;
  double robot_time_s = 0.0;
  std::uint64_t actions = 0;
  std::uint64_t robot_trailer_contacts = 0;
  std::uint64_t failed_grasps = 0;
  std::uint64_t strategies_asked = 0;
  std::uint64_t strategy_steps = 0;  // actions taken by following a branch
  std::string stop_reason;
  std::vector<LeftBox> left;
  sim::World final_world;  // as perceived at the end
};

// A run's strategies, asked for whenever the current one has no step for
// what is seen — at the start, where its tree ends, after an action that
// moved nothing — as the executor asks strategy/next. No strategy ends the
// run, `why` saying why.
struct StrategyChoice {
  std::optional<sim::Strategy> strategy;
  std::string source;  // "hardcoded", "library:A1-1"
  std::string why;
  // Follow the tree even after an action that moved nothing: a precomputed
  // strategy run as it was generated (its tree may plan for such actions).
  bool blind = false;
};
using StrategySource = std::function<plr::Expected<StrategyChoice>(
    const Perceived& seen, const sim::SceneAnalysis& scene, const RunRules& rules)>;

// Strategy H as a source: its first action the rules do not exclude.
StrategySource hardcoded_source(const sim::HardcodedParams& h);

// From the backend's state to the end of the run, each strategy's tree
// followed while it plans for what is seen and its actions move boxes.
// `on_step`, if given, sees each action's outcome.
plr::Expected<Episode> run_strategies(const ActionModel& model, Backend& backend,
                                      const StrategySource& source, const RunLimits& limits,
                                      const std::function<void(const EpisodeStep&)>& on_step = {});

// Strategy H from the backend's state to the end of the run: its ranking
// for each scene, the first action the rules do not exclude.
plr::Expected<Episode> run_hardcoded(const ActionModel& model, Backend& backend,
                                     const sim::HardcodedParams& h, const RunLimits& limits,
                                     const std::function<void(const EpisodeStep&)>& on_step = {});

}  // namespace plr::actions
