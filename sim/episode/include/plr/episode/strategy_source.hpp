// Where a run's strategies come from: asked whenever the current one has no
// step for what is seen — at the start, where its tree ends, after an action
// that moved nothing — as the executor asks strategy/next.
#pragma once

#include <plr/expected.hpp>

#include <functional>
#include <optional>
#include <string>

#include "plr/actions/backend.hpp"
#include "plr/episode/rules.hpp"
#include "plr/sim/hardcoded_strategy.hpp"
#include "plr/sim/strategy.hpp"

namespace plr::episode {

// No strategy ends the run, `why` saying why.
struct StrategyChoice {
  std::optional<sim::Strategy> strategy;
  std::string source;  // "hardcoded", "library:A1-1"
  std::string why;
  // Follow the tree even after an action that moved nothing: a precomputed
  // strategy run as it was generated (its tree may plan for such actions).
  bool blind = false;
};
// `rules` tell which actions moved nothing since the last progress.
using StrategySource = std::function<plr::Expected<StrategyChoice>(
    const actions::Perceived& seen, const sim::SceneAnalysis& scene, const RunRules& rules)>;

// Strategy H as a source: its first action the rules do not exclude.
StrategySource hardcoded_source(const sim::HardcodedParams& h);

}  // namespace plr::episode
