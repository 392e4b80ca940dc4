// plr-chooser (`plr chooser ...`): trains the strategy chooser and shows a
// trained model.
//
//   plr chooser train SETTINGS [--runner local|slurm] [--set key=value]...
//                                                     (configs/train_chooser.yaml)
//   plr chooser show MODEL                            (a .plrm file)
//
// A training started again on the same out folder resumes where it stood.
#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "plr/chooser/model.hpp"
#include "plr/chooser/training/dagger.hpp"
#include "plr/jobs/slurm_runner.hpp"

namespace {

int fail(const std::string& what) {
  std::fprintf(stderr, "plr chooser: %s\n", what.c_str());
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Trains the strategy chooser and shows a trained model"};
  app.name("plr chooser");
  app.require_subcommand(1);
  std::string settings_file, model_file, runner, slurm_task;
  std::vector<std::string> overrides;
  auto* train_cmd = app.add_subcommand(
      "train", "Trains the chooser (DAgger); started again on the same out folder it resumes");
  train_cmd->add_option("settings", settings_file, "Training settings (configs/train_chooser.yaml)")
      ->required();
  train_cmd->add_option("--set", overrides, "Override a setting: KEY=VALUE (repeatable)")
      ->type_name("KEY=VALUE");
  train_cmd
      ->add_option("--runner", runner,
                   "Where the rollouts run: local (child processes) or slurm (a job array per "
                   "state, docs/cluster.md); default: the settings' runner")
      ->check(CLI::IsMember({"local", "slurm"}));
  train_cmd->add_option("--slurm-task", slurm_task, "Run one Slurm array task of this batch file")
      ->group("");  // what a task runs, not for people
  auto* show_cmd = app.add_subcommand("show", "A trained model's figures");
  show_cmd->add_option("model", model_file, "Chooser model (.plrm)")->required();
  CLI11_PARSE(app, argc, argv);

  if (*train_cmd) {
    auto settings = plr::chooser::TrainingSettings::load(settings_file, overrides);
    if (!settings) return fail(settings.error().message);
    if (!slurm_task.empty()) return plr::chooser::run_rollout_task(*settings, slurm_task);
    if (!runner.empty()) settings->runner.kind = *plr::jobs::parse_runner(runner);
    // A task is this command again, from any folder the nodes share.
    std::vector<std::string> task{plr::jobs::this_program(), "train",
                                  std::filesystem::absolute(settings_file).string()};
    for (const auto& o : overrides) task.insert(task.end(), {"--set", o});
    task.push_back("--slurm-task");
    auto summary = plr::chooser::train_chooser(
        *settings,
        [](const std::string& line) {
          std::printf("%s\n", line.c_str());
          std::fflush(stdout);
        },
        task);
    if (!summary) return fail(summary.error().message);
    std::printf(
        "trained: %zu iterations, %zu training and %zu validation states; validation "
        "accuracy %.3f against %.3f for the majority class; %s\n",
        summary->iterations, summary->training_samples, summary->validation_samples,
        summary->validation_accuracy, summary->majority_accuracy,
        (settings->out / "model.plrm").c_str());
    if (!summary->below_minimum.empty())
      std::printf("warning: the model is trained on too little data: %s\n",
                  summary->below_minimum.c_str());
    return 0;
  }
  auto model = plr::chooser::Model::load(model_file);
  if (!model) return fail(model.error().message);
  std::printf(
      "%s: features version %u (%zu), C %g, gamma %g, cross-validated accuracy %.3f, "
      "%zu support vectors, library CRC %08x\n",
      model_file.c_str(), plr::chooser::kFeatureVersion, plr::chooser::kFeatureCount, model->c(),
      model->gamma(), model->cv_accuracy(), model->support_vectors(), model->library_crc());
  if (!model->made_by().empty()) std::printf("made by: %s\n", model->made_by().c_str());
  return 0;
}
