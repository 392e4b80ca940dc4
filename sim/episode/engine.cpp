#include "plr/episode/engine.hpp"

namespace plr::episode {

Engine::Engine(const actions::ActionModel& model, actions::Backend& backend, StrategySource source,
               EngineSettings settings, actions::Memory memory)
    : model_(model),
      backend_(backend),
      source_(std::move(source)),
      settings_(std::move(settings)),
      memory_(std::move(memory)),
      rules_(settings_.limits) {}

plr::Status Engine::run() {
  if (auto ok = checkpoint(); !ok) return ok;
  // The action a lost world interrupted is run again once it is back.
  bool repeating = false;
  for (;;) {
    auto seen = backend_.observe();
    if (!seen) {
      if (auto ok = recover(seen.error()); !ok) return ok;
      continue;
    }
    if (!unloaded_at_start_) {
      unloaded_at_start_ = seen->unloaded;
      episode_.boxes_total = static_cast<std::uint32_t>(seen->world.boxes.size());
    }
    episode_.boxes_unloaded = seen->unloaded - *unloaded_at_start_;
    std::optional<std::string> why = rules_.stop(seen->world.boxes.size());
    const sim::SceneAnalysis scene = why ? sim::SceneAnalysis{} : model_.scene(*seen, memory_);
    if (!why && !repeating) {
      auto end = advance(*seen, scene);
      if (!end) return end.error();
      why = std::move(*end);
    }
    if (why) {
      episode_.stop_reason = std::move(*why);
      if (settings_.classify_left)
        episode_.left = boxes_left(seen->world, seen->q, memory_, model_);
      episode_.final_world = std::move(seen->world);
      for (Observer* o : settings_.observers) o->stopped(episode_);
      return {};
    }
    const sim::Action action = strategy_.nodes[*node_].action;
    for (Observer* o : settings_.observers)
      o->starting(ActionStart{rules_.actions() + 1, action, strategy_, *node_}, episode_);
    repeating = true;
    std::vector<std::string> notes;
    const actions::Reporter reporter{[this](const std::string& step) {
                                       for (Observer* o : settings_.observers) o->progress(step);
                                     },
                                     [this, &notes](const std::string& line) {
                                       notes.push_back(line);
                                       for (Observer* o : settings_.observers) o->note(line);
                                     }};
    auto outcome = model_.run(action, backend_, memory_, reporter);
    if (!outcome) {
      if (auto ok = recover(outcome.error()); !ok) return ok;
      continue;
    }
    repeating = false;
    record(action, scene, std::move(*outcome), std::move(notes));
    if (auto ok = checkpoint(); !ok) {
      if (auto back = recover(ok.error()); !back) return back;
    }
  }
}

plr::Expected<std::optional<std::string>> Engine::advance(const actions::Perceived& seen,
                                                          const sim::SceneAnalysis& scene) {
  // After an action that moved nothing, the tree is not followed blindly:
  // the source is asked again, its rules telling what failed.
  const auto child = node_ && (blind_ || rules_.fresh())
                         ? strategy_.next(*node_, *scene.observation)
                         : std::nullopt;
  if (child) {
    node_ = child;
    ++episode_.strategy_steps;
    return std::optional<std::string>();
  }
  auto choice = source_(seen, scene, rules_);
  if (!choice) return choice.error();
  ++episode_.strategies_asked;
  if (!choice->strategy) return std::optional<std::string>(std::move(choice->why));
  strategy_ = std::move(*choice->strategy);
  from_ = std::move(choice->source);
  blind_ = choice->blind;
  node_ = strategy_.root;
  return std::optional<std::string>();
}

plr::Status Engine::checkpoint() {
  if (!settings_.recovery) return {};  // nothing to come back to
  if (auto ok = settings_.recovery->checkpoint(); !ok) return ok;
  saved_ = Saved{episode_, memory_, rules_};
  return {};
}

plr::Status Engine::recover(const plr::Error& error) {
  if (!settings_.recovery || !settings_.recovery->lost(error)) return error;
  for (Observer* o : settings_.observers) o->lost(error);
  if (auto ok = settings_.recovery->restore(); !ok) return ok;
  const std::uint64_t recoveries = episode_.recoveries + 1;
  episode_ = saved_.episode;
  memory_ = saved_.memory;
  rules_ = saved_.rules;
  episode_.recoveries = recoveries;
  for (Observer* o : settings_.observers) o->restored(episode_);
  return {};
}

void Engine::record(sim::Action action, const sim::SceneAnalysis& scene, actions::Outcome outcome,
                    std::vector<std::string> notes) {
  const actions::Outcome& o = outcome;
  Episode& e = episode_;
  rules_.record(action, o);
  ++e.actions;
  e.planner.add(o.queries);
  if (!o.applicable) {
    ++e.not_applicable;
  } else {
    actions::add_execution(e.pick, e.sweep, action, o);
  }
  e.curve.add(e.robot_time_s, e.boxes_unloaded, o);
  e.robot_time_s += o.robot_time_s;
  e.wasted_s += o.boxes == 0 ? o.robot_time_s : o.plan_model_s;
  e.plan_wall_s += o.plan_wall_s;
  e.robot_trailer_contacts += o.robot_trailer_contacts;
  if (o.sim_time_s > 0) e.sim_time_s = o.sim_time_s;
  e.failed_grasps += o.failed_grasp ? 1 : 0;
  e.boxes_unloaded += o.boxes;
  e.steps.push_back(EpisodeStep{from_, action, *scene.observation, scene.wall_height,
                                scene.pile_height, scene.pile_depth, std::move(outcome),
                                std::move(notes)});
  for (Observer* obs : settings_.observers) obs->recorded(e.steps.back(), e);
}

plr::Expected<Episode> run_episode(const actions::ActionModel& model, actions::Backend& backend,
                                   StrategySource source, EngineSettings settings) {
  Engine engine(model, backend, std::move(source), std::move(settings));
  if (auto ok = engine.run(); !ok) return ok.error();
  return engine.episode();
}

}  // namespace plr::episode
