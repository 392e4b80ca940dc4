// The one loop of an unloading run, online and offline: stop rules -> scene
// -> the strategy's next step (or a new strategy from the source) -> run the
// action -> record, with observers told each step. The backend is the action
// model's (plr/actions/backend.hpp): the in-process rig, or the kernel's bus
// in the executor plug-in, which also recovers a lost simulator.
#pragma once

#include <plr/expected.hpp>

#include <optional>
#include <vector>

#include "plr/actions/action_model.hpp"
#include "plr/episode/episode.hpp"
#include "plr/episode/observer.hpp"
#include "plr/episode/recovery.hpp"
#include "plr/episode/rules.hpp"
#include "plr/episode/strategy_source.hpp"

namespace plr::episode {

struct EngineSettings {
  RunLimits limits;
  std::vector<Observer*> observers;  // told in this order; they outlive the engine's run
  Recovery* recovery = nullptr;      // none: a backend error ends the run
  // Why each box is left (Episode::left) at the end: each tried alone, which
  // costs as much as a few actions' planning.
  bool classify_left = true;
};

class Engine {
 public:
  // The model and backend must outlive the engine. `memory` is what the
  // robot knows at the start (a state's, in training).
  Engine(const actions::ActionModel& model, actions::Backend& backend, StrategySource source,
         EngineSettings settings, actions::Memory memory = {});

  // From the backend's state to the end of the run. An error (the
  // backend's, the source's, a failed recovery's) ends it; the figures so far
  // stay readable.
  plr::Status run();

  const Episode& episode() const { return episode_; }
  const actions::Memory& memory() const { return memory_; }

 private:
  // What a checkpoint keeps, and a recovery brings back.
  struct Saved {
    Episode episode;
    actions::Memory memory;
    RunRules rules;
  };

  // The tree's next step for what is seen, or a new strategy from the
  // source; why the run ends if the source has none.
  plr::Expected<std::optional<std::string>> advance(const actions::Perceived& seen,
                                                    const sim::SceneAnalysis& scene);
  plr::Status checkpoint();
  // `error` ended an observation, an action or a checkpoint: back to the last
  // checkpoint if the recovery gets the world back, else the error.
  plr::Status recover(const plr::Error& error);
  void record(sim::Action action, const sim::SceneAnalysis& scene, actions::Outcome outcome,
              std::vector<std::string> notes);

  const actions::ActionModel& model_;
  actions::Backend& backend_;
  StrategySource source_;
  EngineSettings settings_;
  Episode episode_;
  actions::Memory memory_;
  RunRules rules_;
  Saved saved_;
  std::optional<std::uint32_t> unloaded_at_start_;
  sim::Strategy strategy_;  // the tree being walked
  std::string from_;        // its source
  bool blind_ = false;
  std::optional<std::uint32_t> node_;
};

// A run with a fresh memory, to its end.
plr::Expected<Episode> run_episode(const actions::ActionModel& model, actions::Backend& backend,
                                   StrategySource source, EngineSettings settings = {});

}  // namespace plr::episode
