// What a chooser training runs on (configs/train_chooser.yaml): the library,
// the worlds whose states are labelled, how long each rollout from a state
// runs, and where the data set, model and curve go. Relative paths are
// relative to the current folder, as plr run's --report is.
#pragma once

#include <plr/expected.hpp>

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "plr/chooser/model.hpp"
#include "plr/jobs/runner_settings.hpp"
#include "plr/sim/fidelity.hpp"
#include "plr/sim/generators.hpp"
#include "plr/sim/hardcoded_strategy.hpp"
#include "plr/sim/observation.hpp"
#include "plr/sim/world.hpp"

namespace plr::chooser {

// A starting world: a family and seed ("A1:3"), or a world file.
struct WorldSource {
  std::string name;
  plr::Expected<sim::World> load() const;  // the truth, with masses
  // The world before it settles (cheap: no physics), for fitting the scaling.
  plr::Expected<sim::World> layout() const;
  // A family:seed world's family (its mass prior); none for a file.
  std::optional<sim::EnvFamily> family() const;
};

struct TrainingSettings {
  std::filesystem::path library;
  std::filesystem::path out;  // data.plrd, model.plrm, validation.svg
  std::vector<WorldSource> train, validation;
  std::uint32_t states_per_world = 3;
  std::uint32_t rollout_actions = 4;
  // Rollouts whose rates (boxes per robot-second) differ by at most this
  // share of the larger are a tie: it says nothing about which is better,
  // so the state is not a sample.
  double tie_margin = 0.05;
  // Rollouts whose box counts differ by fewer than this are a tie too: over
  // a few actions one box either way is one grasp's luck, not the strategy.
  std::uint32_t tie_boxes = 2;
  // Each state is rolled out on this many mass particles, since W does not
  // show the masses: its own and particles - 1 drawn from the prior
  // (sim::sample_masses). The label compares the rates pooled over them.
  std::uint32_t particles = 1;
  // The prior of a world file's particles; a family:seed world uses its own.
  std::optional<sim::EnvFamily> mass_prior;
  int workers = 2;
  // Where the rollouts run: child processes (at most `workers` at once) or
  // Slurm job arrays, one per state (docs/cluster.md).
  jobs::RunnerSettings runner;
  sim::ObservationParams observation;
  sim::HardcodedParams h;
  TrainOptions svm;
  // Fewer labelled (non-tie) training states than this still make a model,
  // but one that says so (its made_by, the training's last line, the
  // chooser's log when it loads it): a few dozen states are not "large
  // amounts of data". Not part of hash(): it shapes neither data nor model.
  std::uint32_t min_samples = 500;
  // DAgger goes on until the held-out accuracy stops rising: once the data
  // set holds min_samples, the training ends after `patience` iterations
  // (training worlds) in a row without a new best. 0: every training world.
  std::uint32_t patience = 0;
  // The simulation fidelity the rollouts that label the states run at
  // (docs/fidelity.md): `fidelity: full | adaptive | fast`, full by default.
  sim::Fidelity fidelity = sim::Fidelity::kFull;

  // Of what shapes the data and the model (not of `workers`, `runner` or
  // `out`): a
  // data set made with other settings is not resumed.
  std::uint64_t hash(std::uint32_t library_fingerprint) const;
  // The same as text: what a model records of how it was made.
  std::string describe(std::uint32_t library_fingerprint) const;

  // The file, then each "key=value" override (as --set gives them); errors
  // name the file, line and key.
  static plr::Expected<TrainingSettings> load(const std::filesystem::path& file,
                                              const std::vector<std::string>& overrides = {});
};

}  // namespace plr::chooser
