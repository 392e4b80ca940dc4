#include "plr/episode/strategy_source.hpp"

namespace plr::episode {

StrategySource hardcoded_source(const sim::HardcodedParams& h) {
  return [h](const actions::Perceived&, const sim::SceneAnalysis& scene,
             const RunRules& rules) -> plr::Expected<StrategyChoice> {
    for (const sim::Action a : sim::hardcoded_ranking(scene, h)) {
      if (rules.excluded(a)) continue;
      sim::Strategy s;
      s.name = "H";
      s.nodes.push_back({a, {}});
      return StrategyChoice{std::move(s), "hardcoded", {}};
    }
    return StrategyChoice{std::nullopt, "hardcoded", "every action of H's ranking moved nothing"};
  };
}

}  // namespace plr::episode
