// DAgger-style training of the chooser (the paper's offline phase, step 2):
// from the starting worlds of the training families, at each visited state
// take a snapshot, run the nearest library strategy (NN) and H from it for a
// few actions (jobs in parallel processes, or Slurm array tasks), label the state with whichever
// unloads faster, add it to the data set, retrain M, and go on with M's
// choice. Validation states come first, from other worlds, on the better
// choice's path; each training world is an iteration, after which the
// held-out accuracy is recorded and plotted.
//
// Everything is in settings.out: data.plrd (saved after every state),
// model.plrm and validation.svg (after every iteration). Started again on
// the same folder, a training resumes where it stood; the model is a
// function of the data, so a killed and resumed training ends with the
// model an undisturbed one would.
#pragma once

#include <plr/expected.hpp>

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "plr/chooser/training/settings.hpp"

namespace plr::chooser {

struct TrainingSummary {
  std::size_t validation_samples = 0, training_samples = 0, iterations = 0;
  double validation_accuracy = 0.0, majority_accuracy = 0.0;
  // Empty, or what the model records when its data set is below
  // settings.min_samples ("17 labelled states, below the minimum of 500
  // (min_samples)").
  std::string below_minimum;
};

// `slurm_task`: with settings.runner on Slurm, the command an array task
// runs (this program and its arguments; the runner appends the batch
// file), which calls run_rollout_task.
plr::Expected<TrainingSummary> train_chooser(const TrainingSettings& settings,
                                             const std::function<void(const std::string&)>& log,
                                             const std::vector<std::string>& slurm_task = {});

// One Slurm array task of a training's rollouts: loads the library and the
// robot the settings name, runs its job of `batch_file` and stores the
// result. Returns the exit code.
int run_rollout_task(const TrainingSettings& settings, const std::filesystem::path& batch_file);

}  // namespace plr::chooser
