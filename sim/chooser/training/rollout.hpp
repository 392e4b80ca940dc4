// Rollouts from one state of the trailer: the nearest library strategy and
// strategy H, each for a few actions from the same snapshot, side by side
// as jobs of kind chooser.rollout (plr/jobs). A job carries its state, the
// library entry it follows and its particle's masses, so it runs wherever
// the job engine sends it: in a child forked from the trainer (which
// inherits the loaded robot, planner and library) or in a Slurm array task
// of `plr chooser train --slurm-task`, which loads them itself.
#pragma once

#include <plr/expected.hpp>

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "plr/actions/rig.hpp"
#include "plr/jobs/engine.hpp"
#include "plr/jobs/kinds.hpp"
#include "plr/sim/hardcoded_strategy.hpp"
#include "plr/sim/library.hpp"

namespace plr::chooser {

inline constexpr const char* kRolloutKind = "chooser.rollout";

struct Rollout {
  std::uint64_t actions = 0;
  std::uint32_t boxes = 0;
  double robot_time_s = 0.0;
  std::vector<std::uint8_t> end;  // the TruckState it ended in

  // Boxes per robot second (0 when nothing moved).
  double rate() const { return robot_time_s > 0 ? boxes / robot_time_s : 0.0; }
};

// The library entry it follows (none: H alone), its boxes given `masses`
// (id, kg) first (a particle; empty: the state's own).
struct RolloutJob {
  std::optional<std::uint32_t> entry;
  std::vector<std::pair<std::uint32_t, double>> masses;
};

// What rollouts run on; it outlives the kinds it is added to.
struct RolloutContext {
  actions::Rig& rig;
  const sim::Library& library;
  sim::HardcodedParams h;
  std::uint64_t max_actions = 4;  // actions per rollout at most
};

// One rollout from `state`.
plr::Expected<Rollout> rollout(const RolloutContext& context,
                               const std::vector<std::uint8_t>& state, const RolloutJob& job);

// A job of kind chooser.rollout on `context`: its input checked, its
// rollout run, the result's bytes.
plr::Expected<jobs::Bytes> run_rollout_job(const RolloutContext& context, const jobs::Bytes& input);
// Kind chooser.rollout, run on `context`.
void add_rollout_kind(jobs::Kinds& kinds, const RolloutContext& context);

// One state's rollouts as jobs, keyed `key`-<i>.
std::vector<jobs::Job> rollout_jobs(const std::string& key, const std::vector<std::uint8_t>& state,
                                    const std::vector<RolloutJob>& todo);

// The rollouts a run of those jobs made, in their order; a job that failed
// (a child that died, an action the model refused) is its error.
std::vector<plr::Expected<Rollout>> rollout_results(const jobs::Outcome& outcome);

}  // namespace plr::chooser
