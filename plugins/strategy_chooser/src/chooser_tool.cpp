// plr-chooser (`plr chooser ...`): trains the strategy chooser and shows a
// trained model.
//
//   plr chooser train SETTINGS [--set key=value]...   (configs/train_chooser.yaml)
//   plr chooser show MODEL                            (a .plrm file)
//
// A training started again on the same out folder resumes where it stood.
#include <fmt/format.h>

#include <cstdio>
#include <string>
#include <vector>

#include "plr/chooser/model.hpp"
#include "training/dagger.hpp"

namespace {

int usage() {
  std::fprintf(stderr,
               "usage: plr chooser train SETTINGS [--set key=value]...\n"
               "       plr chooser show MODEL\n");
  return 2;
}

int fail(const std::string& what) {
  std::fprintf(stderr, "plr chooser: %s\n", what.c_str());
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) return usage();
  const std::string command = argv[1];
  if (command == "train") {
    std::vector<std::string> overrides;
    for (int i = 3; i < argc; ++i) {
      if (std::string(argv[i]) == "--set" && i + 1 < argc) {
        overrides.emplace_back(argv[++i]);
      } else {
        return usage();
      }
    }
    auto settings = plr::chooser::TrainingSettings::load(argv[2], overrides);
    if (!settings) return fail(settings.error().message);
    auto summary = plr::chooser::train_chooser(*settings, [](const std::string& line) {
      std::printf("%s\n", line.c_str());
      std::fflush(stdout);
    });
    if (!summary) return fail(summary.error().message);
    std::printf(
        "trained: %zu iterations, %zu training and %zu validation states; validation "
        "accuracy %.3f against %.3f for the majority class; %s\n",
        summary->iterations, summary->training_samples, summary->validation_samples,
        summary->validation_accuracy, summary->majority_accuracy,
        (settings->out / "model.plrm").c_str());
    return 0;
  }
  if (command == "show" && argc == 3) {
    auto model = plr::chooser::Model::load(argv[2]);
    if (!model) return fail(model.error().message);
    std::printf(
        "%s: features version %u (%zu), C %g, gamma %g, cross-validated accuracy %.3f, "
        "%zu support vectors, library CRC %08x\n",
        argv[2], plr::chooser::kFeatureVersion, plr::chooser::kFeatureCount, model->c(),
        model->gamma(), model->cv_accuracy(), model->support_vectors(), model->library_crc());
    return 0;
  }
  return usage();
}
