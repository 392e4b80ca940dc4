// A strategy made below full fidelity, kept honest (issue 45, docs/fidelity.md):
// its tree's value at the level it was made at, over the search's own
// particles, and at full fidelity over fresh particles (mass samples the
// search never used), both recorded in its library entry.
#pragma once

#include <plr/expected.hpp>

#include <cstdint>

#include "plr/actions/rig.hpp"
#include "plr/jobs/store.hpp"
#include "plr/sim/library.hpp"
#include "truck/truck_model.hpp"

namespace plr::generator {

struct Problem;
struct GenerateOptions;

// The fresh particles are the generator's mass particles numbered from
// here on (sim::particle_seed(seed, n)): above any particle count the
// generator takes (1..100), so none of them planned the strategy.
inline constexpr std::uint32_t kFreshParticle = 1000;

struct TreeValue {
  double value = 0.0;  // mean over the particles: negated robot seconds, terminal estimate included
  double boxes = 0.0;  // mean boxes unloaded
};

// `strategy` run from each of the model's first `particles` states (its
// roots) to the horizon, as the search counts a return: each action's robot
// time, and the terminal estimate of the boxes left at the horizon. Where
// the tree has no edge for what a particle shows, the rest is valued as the
// search values a belief it did not expand (the lower heuristic: the rest
// of the horizon wasted). Throws SimulationError as TruckModel::step.
TreeValue tree_value(const TruckModel& model, const sim::Strategy& strategy, std::size_t particles);

// `strategy`'s value at full fidelity on `particles` fresh particles of
// `problem`: for a fresh trailer its W with fresh masses, settled at full
// fidelity; for a continuation each starting state (in turn) with the
// masses redrawn. Simulated by `simulator` (its fidelity set to full for
// the time), results kept in `store` under full fidelity's keys. `at_level`
// is the strategy's value at the level it was made at (tree_value on the
// search's model).
plr::Expected<sim::FidelityCheck> check_at_full(const Problem& problem,
                                                const sim::Strategy& strategy,
                                                const GenerateOptions& options, TreeValue at_level,
                                                std::uint32_t particles, actions::Rig& rig,
                                                Simulator& simulator,
                                                const plr::jobs::Store* store);

}  // namespace plr::generator
