#include "plr/episode/open_loop.hpp"

#include "plr/episode/engine.hpp"

namespace plr::episode {

namespace {
constexpr const char* kOpenLoop = "open loop";
}  // namespace

plr::Expected<OpenLoopRun> run_open_loop(const actions::ActionModel& model,
                                         actions::Backend& backend, actions::Memory& memory,
                                         const std::optional<sim::Strategy>& strategy,
                                         const sim::HardcodedParams& h, std::uint64_t max_actions) {
  // The strategy leads from its root while its tree plans for what is seen
  // and its actions move boxes; then H, to the end.
  const StrategySource hardcoded = hardcoded_source(h);
  bool led = false;
  StrategySource source = [&](const actions::Perceived& seen, const sim::SceneAnalysis& scene,
                              const RunRules& rules) -> plr::Expected<StrategyChoice> {
    if (strategy && !led) {
      led = true;
      return StrategyChoice{*strategy, kOpenLoop, {}};
    }
    return hardcoded(seen, scene, rules);
  };
  EngineSettings settings;
  settings.limits = {max_actions, 24};
  settings.classify_left = false;  // only the figures are compared
  Engine engine(model, backend, std::move(source), std::move(settings), std::move(memory));
  const auto ran = engine.run();
  memory = engine.memory();
  if (!ran) return ran.error();
  OpenLoopRun run;
  run.actions = engine.episode().actions;
  run.robot_time_s = engine.episode().robot_time_s;
  for (const EpisodeStep& s : engine.episode().steps) {
    run.boxes += s.outcome.boxes;
    if (s.source == kOpenLoop) ++run.strategy_steps;
  }
  return run;
}

}  // namespace plr::episode
