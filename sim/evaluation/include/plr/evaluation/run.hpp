// One run of the evaluation: a method on one seed of an environment, from
// its starting world to the horizon, in process (the action model on the
// simulation, plr/actions/rig.hpp). Its result is a JSON object with the
// unloading curve and the figures of the paper's Tables I and II.
#pragma once

#include <plr/expected.hpp>

#include <cstdint>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "plr/actions/rig.hpp"
#include "plr/chooser/model.hpp"
#include "plr/chooser/nearest.hpp"
#include "plr/evaluation/settings.hpp"
#include "plr/sim/chain.hpp"
#include "plr/sim/library.hpp"

namespace plr::evaluation {

// The library L and the chooser's model M, as the methods need them.
struct Resources {
  sim::Library library;
  // Each strategy for a fresh trailer with its continuations grafted
  // (plr/sim/chain.hpp): what open-loop and expected-offline follow; by
  // entry index (a continuation's is its own strategy).
  std::vector<sim::Chain> chains;
  std::optional<chooser::Model> model;
  std::optional<chooser::LibraryIndex> index;
};

// Errors are one line naming the file and, when it is missing, the commands
// that make it.
plr::Expected<Resources> load_resources(const EvaluationSettings& settings);

struct RunSpec {
  std::size_t environment = 0;  // index into settings.environments
  Method method = Method::kHardcoded;
  std::uint64_t seed = 1;
  // The same run at full fidelity, beside one at the settings' lower level.
  bool full_check = false;
};

// "A1_PLR_seed3" ("A1_PLR_seed3_full" for a full-fidelity check): the
// run's key in the result store.
std::string run_key(const EvaluationSettings& settings, const RunSpec& run);
// Whether the method runs on the environment (open-loop and
// expected-offline on training environments only).
bool applies(const EvaluationSettings& settings, const RunSpec& run);

// Every run of the evaluation of `seeds` seeds, in order: each applicable
// environment, method and seed, then the full-fidelity checks of the first
// fidelity_check_seeds seeds when the settings' fidelity is below full.
std::vector<RunSpec> plan_runs(const EvaluationSettings& settings, std::uint64_t seeds);

// The world the run starts from (with masses), and its name
// ("A1-2, masses of seed 3", "A2:3").
struct StartWorld {
  sim::World truth;
  std::string name;
  const sim::LibraryEntry* entry = nullptr;  // the training world's library entry
};
plr::Expected<StartWorld> start_world(const EvaluationSettings& settings,
                                      const Resources& resources, const RunSpec& run);

// What decides a run's result besides its key (the cap, the limits, the
// thresholds, the library and model): runs made under other conditions are
// not the same runs, however they are named.
nlohmann::json run_conditions(const EvaluationSettings& settings, const Resources& resources);

// Runs it on `rig` (its simulation is replaced), at the settings' fidelity
// or, for a check, at full. Errors of the run itself (a backend's) come back
// in the result's "error"; the result says its "fidelity" and, for a check,
// "fidelity_check": true.
nlohmann::json run_one(actions::Rig& rig, const EvaluationSettings& settings,
                       const Resources& resources, const RunSpec& run);

}  // namespace plr::evaluation
