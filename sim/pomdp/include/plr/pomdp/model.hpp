// The generative POMDP interface every solver here runs on: sample one step
// from a state, and expand a belief by one action. No robot in it: a truck
// model implements the same interface with simulated worlds as states.
#pragma once

#include <cstdint>
#include <random>
#include <vector>

#include "plr/pomdp/belief.hpp"

namespace plr::pomdp {

using Rng = std::mt19937_64;

struct Step {
  StateId next = 0;
  ObsId observation = 0;
  double reward = 0.0;
  bool terminal = false;  // `next` ends the episode
};

// One observation branch of a belief expanded by an action.
struct Outcome {
  ObsId observation = 0;
  double probability = 0.0;
  Belief next;
};

struct Expansion {
  double reward = 0.0;  // expected immediate reward under the belief
  std::vector<Outcome> outcomes;
};

class GenerativeModel {
 public:
  virtual ~GenerativeModel() = default;

  virtual int num_actions() const = 0;
  virtual int num_observations() const = 0;
  // In [0, 1). A goal-directed model returns 1 and non-positive rewards
  // (costs), and reaches terminal goal states.
  virtual double discount() const = 0;
  // Bounds on any one step's reward; solvers scale exploration with them.
  virtual double min_reward() const = 0;
  virtual double max_reward() const = 0;

  virtual Belief initial_belief() const = 0;
  virtual bool is_terminal(StateId state) const = 0;
  virtual Step step(StateId state, ActionId action, Rng& rng) const = 0;

  // The belief after `action`, split by observation. The default simulates
  // every particle `samples_per_particle` times and groups the results by
  // observation (weights stay proportional to how often each state was
  // reached); models with known probabilities override it with the exact
  // Bayes update.
  virtual Expansion expand(const Belief& belief, ActionId action, Rng& rng) const;

  // Every action of `belief` is about to be expanded (a search node's
  // expansion). A model whose steps are costly may compute them all at once
  // here, in parallel; the steps must come out as they would one by one.
  virtual void prefetch(const Belief& /*belief*/) const {}
  // True when `action` is known to be no better than the belief's best
  // other action, so a search need not consider it: for example an action
  // that leaves every particle exactly where it was and only spends time
  // (the same steps after it are as good without it). Asked after
  // prefetch(); a solver keeps all actions when every one is dominated.
  virtual bool dominated(const Belief& /*belief*/, ActionId /*action*/) const { return false; }

  // How many times the default expand() simulates each particle.
  int samples_per_particle = 1;
};

// Sample a state from a belief.
StateId sample_state(const Belief& belief, Rng& rng);

// The belief after acting and observing: the matching outcome of expand(),
// or an empty belief when the observation has probability zero under it.
Belief update_belief(const GenerativeModel& model, const Belief& belief, ActionId action,
                     ObsId observation, Rng& rng);

// True when every particle of the belief is terminal.
bool is_terminal(const GenerativeModel& model, const Belief& belief);

}  // namespace plr::pomdp
