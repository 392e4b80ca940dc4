// States strategy H visits from a family's environments: where the
// benchmarks that run single actions start from.
#pragma once

#include <algorithm>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "bench_util.hpp"
#include "plr/actions/action_model.hpp"
#include "plr/actions/in_process.hpp"
#include "plr/expected.hpp"
#include "plr/planning/lattice_planner.hpp"
#include "plr/sim/generators.hpp"
#include "plr/sim/hardcoded_strategy.hpp"
#include "plr/sim/observation.hpp"

namespace plr::bench {

struct HState {
  sim::EnvFamily family;
  std::uint64_t seed = 0;
  int after = 0;  // H actions that unloaded something before it
  std::shared_ptr<const actions::UnloaderSimulation::Saved> saved;
  actions::Memory memory;
  std::size_t boxes = 0;
  std::string observation;
};

// How H walks and where it stops to save a state.
struct HWalk {
  const sim::RobotModel& robot;
  planning::LatticePlanner& planner;
  const actions::ActionModel& model;
  sim::HardcodedParams h;
  actions::InProcessOptions backend{};
  int every = 10;          // H actions that unloaded something between states
  int max_h_actions = 40;  // per seed
  int states_per_seed = 2;
  actions::InProcessStats* stats = nullptr;  // summed over the walks, if set
};

inline void add(actions::InProcessStats& sum, const actions::InProcessStats& s) {
  sum.queries += s.queries;
  sum.motions += s.motions;
  sum.checker_s += s.checker_s;
  sum.plan_s += s.plan_s;
  sum.sample_s += s.sample_s;
  sum.execute_s += s.execute_s;
  sum.observe_s += s.observe_s;
}

// Up to `count` states of one seed: the first before any action, then one
// every `every` actions that unloaded something (an action that moved
// nothing is excluded until one does, as the executor does).
inline plr::Expected<std::vector<HState>> visit_seed(const HWalk& w, sim::EnvFamily family,
                                                     std::uint64_t seed, int count,
                                                     Progress& progress) {
  std::vector<HState> states;
  actions::UnloaderSimulation simulation(w.robot, sim::make_environment(family, seed));
  actions::InProcessBackend backend(simulation, w.planner, w.backend);
  actions::Memory memory;
  std::vector<sim::Action> excluded;
  const std::string name = std::string(to_string(family)) + " seed " + std::to_string(seed);
  for (int done = 0; done <= w.max_h_actions && static_cast<int>(states.size()) < count;) {
    const sim::World seen = simulation.perceived();
    if (seen.boxes.empty()) break;
    const sim::SceneAnalysis scene = sim::analyse(seen, w.model.options().observation);
    if (!scene.observation) break;
    if (done % w.every == 0 && excluded.empty()) {
      states.push_back(HState{family, seed, done, simulation.save(), memory, seen.boxes.size(),
                              sim::to_string(*scene.observation)});
      progress.step(name + ": state after " + std::to_string(done) + " H actions");
      if (static_cast<int>(states.size()) >= count) break;
    }
    std::optional<sim::Action> action;
    for (const sim::Action a : sim::hardcoded_ranking(scene, w.h)) {
      if (std::find(excluded.begin(), excluded.end(), a) == excluded.end()) {
        action = a;
        break;
      }
    }
    if (!action) break;
    const auto out = w.model.run(*action, backend, memory);
    if (!out) return plr::make_error(out.error().code, name + ": " + out.error().message);
    if (out->boxes > 0) {
      excluded.clear();
      ++done;
    } else {
      excluded.push_back(*action);
    }
  }
  if (w.stats != nullptr) add(*w.stats, backend.stats());
  return states;
}

// `per_family` states of each family, `states_per_seed` from each seed from
// `first_seed` on (at most 20 seeds).
inline plr::Expected<std::map<sim::EnvFamily, std::vector<HState>>> visit_families(
    const HWalk& w, const std::vector<sim::EnvFamily>& families, int per_family,
    std::uint64_t first_seed, Progress& progress) {
  std::map<sim::EnvFamily, std::vector<HState>> states;
  for (const sim::EnvFamily f : families) {
    auto& list = states[f];
    for (std::uint64_t s = first_seed;
         static_cast<int>(list.size()) < per_family && s < first_seed + 20; ++s) {
      const int want = std::min(w.states_per_seed, per_family - static_cast<int>(list.size()));
      auto more = visit_seed(w, f, s, want, progress);
      if (!more) return more.error();
      list.insert(list.end(), more->begin(), more->end());
    }
  }
  return states;
}

}  // namespace plr::bench
