#include "plr/actions/open_loop.hpp"

#include "plr/actions/episode.hpp"

namespace plr::actions {

plr::Expected<OpenLoopRun> run_open_loop(const ActionModel& model, Backend& backend, Memory& memory,
                                         const std::optional<sim::Strategy>& strategy,
                                         const sim::HardcodedParams& h, std::uint64_t max_actions) {
  OpenLoopRun run;
  RunRules rules({max_actions, 24});
  // The strategy leads from its root while its tree plans for what is seen
  // and its actions move boxes; then H, to the end.
  bool following = strategy.has_value();
  std::optional<std::uint32_t> node;
  for (;;) {
    auto seen = backend.observe();
    if (!seen) return seen.error();
    if (rules.stop(seen->world.boxes.size())) return run;
    const sim::SceneAnalysis scene = model.scene(*seen, memory);
    std::optional<sim::Action> action;
    if (following) {
      if (!node) {
        node = strategy->root;
      } else {
        node = rules.fresh() ? strategy->next(*node, *scene.observation) : std::nullopt;
      }
      following = node.has_value();
      if (following) {
        action = strategy->nodes[*node].action;
        ++run.strategy_steps;
      }
    }
    if (!action) {
      for (const sim::Action a : sim::hardcoded_ranking(scene, h)) {
        if (!rules.excluded(a)) {
          action = a;
          break;
        }
      }
    }
    if (!action) return run;
    auto out = model.run(*action, backend, memory);
    if (!out) return out.error();
    rules.record(*action, *out);
    ++run.actions;
    run.boxes += out->boxes;
    run.robot_time_s += out->robot_time_s;
  }
}

}  // namespace plr::actions
