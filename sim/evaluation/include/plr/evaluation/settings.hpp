// What an evaluation runs (configs/evaluate.yaml): the library L and the
// chooser's model M, the environments, the methods, the seeds, and the
// robot-time horizon each run is cut at. Relative paths are relative to the
// current folder, as plr run's --report is.
#pragma once

#include <plr/expected.hpp>

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "plr/jobs/runner_settings.hpp"
#include "plr/sim/fidelity.hpp"
#include "plr/sim/generators.hpp"
#include "plr/sim/hardcoded_strategy.hpp"
#include "plr/sim/observation.hpp"

namespace plr::evaluation {

// The paper's five methods (docs/evaluation.md says what each runs).
enum class Method { kHardcoded, kNearest, kOpenLoop, kExpectedOffline, kPlr };
const char* to_string(Method method);  // "H", "NN", "open-loop", "expected-offline", "PLR"
std::optional<Method> parse_method(const std::string& name);
// Open-loop and expected-offline run the precomputed strategies of the
// world they were made for: training environments only.
bool needs_training_world(Method method);

struct Environment {
  std::string name;                             // "A1"; names the plot and the result files
  sim::EnvFamily family = sim::EnvFamily::kA1;  // layouts and the mass prior
  // Training: its worlds are the library's (entries of `family`), with
  // masses drawn anew for each seed. Else the family's generator (or
  // `world`) for each seed.
  bool training = false;
  std::filesystem::path world;  // a world file instead of the generator (masses per seed)
};

struct EvaluationSettings {
  std::filesystem::path library;
  std::filesystem::path model;
  std::vector<Environment> environments;
  std::vector<Method> methods;
  std::uint64_t first_seed = 1;
  std::uint64_t seeds = 10;
  std::uint64_t quick_seeds = 3;
  double max_robot_time_s = 3600;  // the robot-time cap each run is cut at
  // --quick: a look at the start of every run, not whole trailers.
  double quick_max_robot_time_s = 300;
  std::uint64_t max_actions = 0;  // 0: no limit
  unsigned workers = 2;
  double timeout_s = 3600;  // wall seconds per run, a safety net
  double max_distance = 0;  // PLR: NN beyond it goes to H; 0: no limit
  // How accurately the runs simulate (docs/fidelity.md). Below full, the
  // first `fidelity_check_seeds` seeds of every environment and method also
  // run at full fidelity, and the report gives the difference beside the
  // results: what the cheaper simulation changed.
  sim::Fidelity fidelity = sim::Fidelity::kFull;
  std::uint64_t fidelity_check_seeds = 1;
  sim::ObservationParams observation;
  sim::HardcodedParams h;
  jobs::RunnerSettings runner;  // where the runs run: local processes or Slurm

  // The file, then each "key=value" override (as --set gives them); errors
  // name the file, line and key.
  static plr::Expected<EvaluationSettings> load(const std::filesystem::path& file,
                                                const std::vector<std::string>& overrides = {});
};

}  // namespace plr::evaluation
