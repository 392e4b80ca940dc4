// One strategy from one world: POMHDP (plr_pomdp) on the truck model over
// the world's mass particles, to a budget of trials; its lower-bound policy
// unrolled to the horizon becomes the strategy, with the root's bounds, the
// anytime curve and how it was made (a library entry, plr/sim/library.hpp).
//
// The result depends on the problem and the options only: the budget is in
// trials, every simulation is a function of its (state, action), and the
// solver is deterministic. So neither the number nor the speed of the
// workers, nor a resume from the stored results, changes it; only the times in the
// curve and provenance differ.
#pragma once

#include <plr/expected.hpp>

#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "plr/jobs/store.hpp"
#include "plr/pomdp/policy_tree.hpp"
#include "plr/sim/generators.hpp"
#include "plr/sim/library.hpp"
#include "truck/simulator.hpp"
#include "truck/truck_model.hpp"

namespace plr::generator {

struct Problem {
  std::string name;
  std::string family;
  std::uint64_t world_seed = 0;
  sim::World world;                   // W (masses 0)
  std::vector<sim::World> particles;  // W with each particle's masses
  std::string observation_json = "{}";
  // A continuation: its particles' starting states (a leaf belief of
  // `parent`, reached by the observations `leaf`), in place of `particles`
  // at rest; `particle_ids` says which of the generator's mass particles
  // each is. For a fresh trailer all three are empty (ids 0, 1, ...).
  std::string parent;
  std::vector<sim::Observation> leaf;
  std::vector<SimOutcome> starts;
  std::vector<std::uint32_t> particle_ids;
};

// Where a strategy's tree ends for some of its particles: after the
// observations `path` from its root (the last one has no edge), or where the
// trailer became empty (`empty`: the path stops before the goal). The
// particles that end there share the path, so they are one belief of the
// search: the one a run that saw those observations is in.
struct Leaf {
  std::vector<sim::Observation> path;
  bool empty = false;
  std::vector<std::uint32_t> particles;  // the generator's mass particles
  std::vector<SimOutcome> states;        // theirs, in the same order
  double share = 0.0;                    // of the strategy's particles
};

// W^t = make_environment(family, world_seed); the particles are W with
// masses from the family's prior (sample_masses, seeds from `seed`).
Problem make_problem(sim::EnvFamily family, std::uint64_t world_seed, int particles,
                     std::uint64_t seed);
// A given world W (masses dropped), its masses from `family`'s prior.
Problem make_problem(const sim::World& world, sim::EnvFamily family, std::string name,
                     int particles, std::uint64_t seed);

struct GenerateOptions {
  TruckOptions truck;
  double epsilon1 = 10.0, epsilon2 = 10.0;
  std::uint64_t seed = 1;
  std::uint64_t trials = 8;  // the budget
  double target_gap = 0.5;   // s; stop early once the root's bounds are this close
  // Unroll the policy through beliefs no trial expanded (costs their
  // simulations); off, the strategy ends there and its runner's fallback
  // (strategy H) goes on.
  bool complete_tree = true;
  // A safety net only: a run that hits it depends on the machine's speed.
  double max_wall_s = std::numeric_limits<double>::infinity();
  // The simulation fidelity the search simulates at (docs/fidelity.md). Below
  // full, the strategy is then re-evaluated at full fidelity on as many
  // fresh particles as it was made with, and the entry records both values.
  sim::Fidelity fidelity = sim::Fidelity::kFull;
};

struct GenerateProgress {
  std::uint64_t trials = 0, trial_budget = 0;
  std::size_t nodes = 0;
  std::uint64_t results = 0, simulated = 0;
  double lower = 0.0, upper = 0.0;
  double wall_s = 0.0;
  bool unrolling = false;  // the budget is spent; the policy is being unrolled
};

struct GenerateResult {
  sim::LibraryEntry entry;
  pomdp::PolicyTree tree;
  std::vector<Leaf> leaves;     // in path order
  std::uint64_t simulated = 0;  // by this run (the rest came from the store)
  double simulated_robot_s = 0.0;
  double simulated_wall_s = 0.0;  // inside the workers
  // Below full fidelity: the re-evaluation at full fidelity, its wall time
  // and this process's CPU time (all of it when the simulations run here).
  double check_wall_s = 0.0;
  double check_cpu_s = 0.0;
};

// `rig` makes the particles' starting states; `simulator` runs the
// actions (both set to options.fidelity), its results kept in `store` (checkpoint_dir/<name>) if
// given. `on_progress` is called after every trial; returning false stops the generation
// (PLR_ERR_CANCELLED). An error says which simulation failed.
plr::Expected<GenerateResult> generate(
    const Problem& problem, const GenerateOptions& options, actions::Rig& rig, Simulator& simulator,
    const plr::jobs::Store* store,
    const std::function<bool(const GenerateProgress&)>& on_progress = {});

// The leaves of `entry`'s strategy run on `problem`'s particles (the
// problem it was made for), replayed with the truck model: a resumed
// generation's way to its continuations' beliefs. The simulations come from
// `store` (the entry's result store) when it has them, at the fidelity the
// entry was made at.
plr::Expected<std::vector<Leaf>> replay_leaves(const Problem& problem,
                                               const sim::LibraryEntry& entry,
                                               const GenerateOptions& options, actions::Rig& rig,
                                               Simulator& simulator, const plr::jobs::Store* store);

// The leaves that get a continuation: every leaf (trailer not empty) that at
// least `min_share` of the particles reach, and always the one most reach
// (on a tie, the one with the most boxes left; then the first in path
// order). Indices into `leaves`.
std::vector<std::size_t> continued_leaves(const std::vector<Leaf>& leaves, double min_share);

// The problem of the continuation of `parent` at `leaves[index]`: named
// "<parent>.<index + 1>", its particles the leaf's states, its W the world as
// the robot perceives it on the leaf's first particle (`rig` restores it).
plr::Expected<Problem> continuation(const Problem& parent, const std::vector<Leaf>& leaves,
                                    std::size_t index, actions::Rig& rig);

// The policy tree with the truck's labels (observations of an empty
// trailer end a branch).
sim::Strategy to_strategy(const pomdp::PolicyTree& tree, const std::string& name);

}  // namespace plr::generator
