// DAgger-style training of the chooser (the paper's offline phase, step 2):
// from the starting worlds of the training families, at each visited state
// take a snapshot, run the nearest library strategy (NN) and H from it for a
// few actions (in parallel processes), label the state with whichever
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

#include <functional>
#include <string>

#include "plr/chooser/training/settings.hpp"

namespace plr::chooser {

struct TrainingSummary {
  std::size_t validation_samples = 0, training_samples = 0, iterations = 0;
  double validation_accuracy = 0.0, majority_accuracy = 0.0;
};

plr::Expected<TrainingSummary> train_chooser(const TrainingSettings& settings,
                                             const std::function<void(const std::string&)>& log);

}  // namespace plr::chooser
