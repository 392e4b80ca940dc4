// The truck as a goal-directed POMDP for plr_pomdp: a state is a simulated
// trailer (a particle: the visible world with masses drawn from the
// family's prior) after some actions; the 12 abstract actions; the 18
// semantic observations of the scene after an action, and a 19th for an
// empty trailer. Cost (negated reward) = robot time; a state is terminal
// when the trailer is empty (the goal) or the horizon is reached, where
// the step into it also pays a terminal estimate for the boxes left.
//
// Simulating one action on one particle is the costly step: each (state,
// action) is simulated once (results cached by work_key(), and kept in
// the result store if there is one), and a node's expansion hands all its
// particles × 12 actions to the Simulator as one batch (prefetch()).
#pragma once

#include <cstdint>
#include <map>
#include <stdexcept>
#include <unordered_map>
#include <utility>
#include <vector>

#include "plr/jobs/store.hpp"
#include "plr/pomdp/model.hpp"
#include "truck/simulator.hpp"

namespace plr::generator {

struct TruckOptions {
  int horizon = 6;  // actions
  // The terminal estimate: robot seconds each box left at the horizon is
  // worth (more than an action takes per box, so unloading pays).
  double seconds_per_box = 20.0;
  // A typical action's robot time: the scale of the inadmissible heuristics.
  double action_s = 15.0;
  // The least robot time any action takes (finding it not applicable):
  // what the admissible anchor charges a non-goal state.
  double min_action_s = 0.5;
  // The most boxes one action unloads, and the least robot time a box
  // takes: the anchor assumes each action left before the horizon unloads
  // this many, each box at this cost (it stays admissible while no action
  // does better: the fastest measured were 43 boxes in one sweep, and
  // 0.46 s a box over a whole sweep). Without a cost per box the anchor
  // rates a not-applicable action (0.5 s, nothing unloaded) above every
  // action that unloads, and the trials spend themselves on those.
  double max_boxes_per_action = 60.0;
  double min_seconds_per_box = 0.2;
};

// A simulation the generator cannot do without failed (the message says which).
class SimulationError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class TruckModel final : public pomdp::GenerativeModel {
 public:
  static constexpr pomdp::ObsId kGoalObservation = sim::kNumObservations;

  struct State {
    StateBytes bytes;
    std::uint64_t hash = 0;
    int depth = 0;
    std::uint32_t boxes_left = 0;
    double highest_stack_m = 0.0;
    int observation = kEmptyObservation;
  };

  // `roots`: each particle's starting state (actions::start_state), equally
  // likely. The simulator (and store) must outlive the model.
  TruckModel(Simulator& simulator, const std::vector<SimOutcome>& roots, TruckOptions options,
             const plr::jobs::Store* store = nullptr);

  int num_actions() const override { return sim::kNumActions; }
  int num_observations() const override { return sim::kNumObservations + 1; }
  double discount() const override { return 1.0; }
  double min_reward() const override;
  double max_reward() const override { return 0.0; }
  pomdp::Belief initial_belief() const override;
  bool is_terminal(pomdp::StateId state) const override;
  // Throws SimulationError when the simulation fails.
  pomdp::Step step(pomdp::StateId state, pomdp::ActionId action, pomdp::Rng& rng) const override;
  void prefetch(const pomdp::Belief& belief) const override;
  // An action that was not applicable and changed nothing on every particle
  // (the same state, 0.5 s later) is dominated.
  bool dominated(const pomdp::Belief& belief, pomdp::ActionId action) const override;

  const State& state(pomdp::StateId id) const { return states_[static_cast<std::size_t>(id)]; }
  const TruckOptions& options() const { return options_; }
  // Distinct (state, action) results known, and how many this process had simulated.
  std::uint64_t results() const { return results_.size(); }
  std::uint64_t simulated() const { return simulated_; }
  double simulated_robot_s() const { return simulated_robot_s_; }
  // What simulating them took the workers (wall time inside the workers).
  double simulated_wall_s() const { return simulated_wall_s_; }

 private:
  pomdp::StateId intern(const SimOutcome& o, int depth) const;
  // Simulates what the cache lacks, as one batch.
  void fill(const std::vector<SimRequest>& requests) const;

  Simulator& simulator_;
  TruckOptions options_;
  const plr::jobs::Store* store_;
  std::size_t roots_ = 0;
  mutable std::vector<State> states_;
  mutable std::map<std::pair<std::uint64_t, int>, pomdp::StateId> index_;  // (hash, depth)
  mutable std::unordered_map<std::uint64_t, SimOutcome> results_;          // by work_key
  mutable std::map<std::pair<pomdp::StateId, pomdp::ActionId>, pomdp::Step> steps_;
  mutable std::uint64_t simulated_ = 0;
  mutable double simulated_robot_s_ = 0.0;
  mutable double simulated_wall_s_ = 0.0;
};

}  // namespace plr::generator
