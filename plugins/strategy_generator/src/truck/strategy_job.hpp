// One world's strategy as a job of the job engine (kind generator.strategy):
// how the generator hands the strategies of a library to a cluster, each an
// array task of `plr_sim_worker --slurm-task` (docs/cluster.md). The input
// names the world and every option the strategy depends on; the output is
// the library entry, as a one-entry library (plr/sim/library.hpp). The
// task's simulations run in its own process, their results kept in the
// world's store (checkpoint_dir/<world>) on the shared filesystem, so a task
// that is run again goes on where the last attempt stopped.
#pragma once

#include <plr/expected.hpp>

#include <cstdint>
#include <string>

#include "plr/jobs/job.hpp"
#include "plr/jobs/kinds.hpp"
#include "plr/sim/generators.hpp"
#include "truck/generate.hpp"

namespace plr::generator {

inline constexpr const char* kStrategyKind = "generator.strategy";

// A family's world by seed, or a world file with a family's mass prior.
struct WorldSpec {
  sim::EnvFamily family = sim::EnvFamily::kA1;
  std::uint64_t seed = 1;
  std::string file;
};

struct StrategyJob {
  WorldSpec world;
  int particles = 5;
  std::uint64_t seed = 1;
  GenerateOptions options;
  std::string observation_json = "{}";
  std::string checkpoint_dir;
};

// The problem the job's world poses (a world file that cannot be read is
// an error naming it).
plr::Expected<Problem> make_problem(const StrategyJob& job);

jobs::Bytes encode(const StrategyJob& job);
// Bytes from a store or another process: errors name what is wrong.
plr::Expected<StrategyJob> decode_strategy_job(const jobs::Bytes& bytes);

// Kind generator.strategy, generated in this process.
void add_strategy_job(jobs::Kinds& kinds);

}  // namespace plr::generator
