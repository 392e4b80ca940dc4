// An explicit POMDP: sparse transition and observation tables, rewards per
// transition. What the Cassandra and POMDPX readers produce; its expand() is
// the exact Bayes update.
#pragma once

#include <string>
#include <vector>

#include "plr/pomdp/model.hpp"

namespace plr::pomdp {

struct Transition {
  StateId next = 0;
  double probability = 0.0;
  // Expected reward of this transition (over observations when the file's
  // reward depends on them).
  double reward = 0.0;
};

struct ObsProb {
  ObsId observation = 0;
  double probability = 0.0;
};

class TabularModel final : public GenerativeModel {
 public:
  TabularModel() = default;
  TabularModel(int states, int actions, int observations);

  int num_states() const { return num_states_; }
  int num_actions() const override { return num_actions_; }
  int num_observations() const override { return num_observations_; }
  double discount() const override { return discount_; }
  double min_reward() const override { return min_reward_; }
  double max_reward() const override { return max_reward_; }

  Belief initial_belief() const override { return initial_; }
  bool is_terminal(StateId state) const override { return terminal_[state] != 0; }
  Step step(StateId state, ActionId action, Rng& rng) const override;
  Expansion expand(const Belief& belief, ActionId action, Rng& rng) const override;

  // Sparse rows, sorted by next state / observation.
  const std::vector<Transition>& transitions(ActionId a, StateId s) const {
    return transitions_[row(a, s)];
  }
  const std::vector<ObsProb>& observations(ActionId a, StateId next) const {
    return observations_[row(a, next)];
  }
  // Expected reward of acting in a state.
  double reward(ActionId a, StateId s) const { return expected_reward_[row(a, s)]; }

  std::vector<std::string> state_names, action_names, observation_names;

  // Builders (used by the readers and tests); finish() completes the model.
  void set_discount(double discount) { discount_ = discount; }
  void set_initial_belief(Belief belief) { initial_ = std::move(belief); }
  std::vector<Transition>& mutable_transitions(ActionId a, StateId s) {
    return transitions_[row(a, s)];
  }
  std::vector<ObsProb>& mutable_observations(ActionId a, StateId next) {
    return observations_[row(a, next)];
  }
  // Computes expected rewards, reward range and terminal states: a state is
  // terminal when every action keeps it where it is and earns nothing.
  void finish();

 private:
  std::size_t row(int a, int s) const {
    return static_cast<std::size_t>(a) * static_cast<std::size_t>(num_states_) +
           static_cast<std::size_t>(s);
  }

  int num_states_ = 0, num_actions_ = 0, num_observations_ = 0;
  double discount_ = 0.95;
  double min_reward_ = 0.0, max_reward_ = 0.0;
  Belief initial_;
  std::vector<std::vector<Transition>> transitions_;  // [a * S + s]
  std::vector<std::vector<ObsProb>> observations_;    // [a * S + s']
  std::vector<double> expected_reward_;               // [a * S + s]
  std::vector<char> terminal_;
};

}  // namespace plr::pomdp
