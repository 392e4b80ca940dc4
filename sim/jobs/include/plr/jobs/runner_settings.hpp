// Which runner a program's settings ask for: `runner: local | slurm`, and
// for Slurm a `slurm:` map (docs/cluster.md). The same two keys in every
// settings file whose work is jobs (evaluation, chooser training).
#pragma once

#include <plr/yaml_reader.hpp>

#include <string>

#include "plr/jobs/slurm_runner.hpp"

namespace plr::jobs {

struct RunnerSettings {
  enum class Kind { kLocal, kSlurm } kind = Kind::kLocal;
  SlurmOptions slurm;
};

// The keys read_runner_settings reads, for the settings' list of known keys.
inline constexpr const char* kRunnerKey = "runner";
inline constexpr const char* kSlurmKey = "slurm";

// Reads `runner` and `slurm` of `top` (both optional); errors go to the
// document, naming the line.
void read_runner_settings(const plr::yaml::Map& top, RunnerSettings& out);

// "local" or "slurm": what `--runner` accepts; nullopt for anything else.
std::optional<RunnerSettings::Kind> parse_runner(const std::string& name);

}  // namespace plr::jobs
