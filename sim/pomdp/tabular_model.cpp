#include "plr/pomdp/tabular_model.hpp"

#include <algorithm>
#include <limits>

namespace plr::pomdp {

TabularModel::TabularModel(int states, int actions, int observations)
    : num_states_(states),
      num_actions_(actions),
      num_observations_(observations),
      transitions_(static_cast<std::size_t>(states) * static_cast<std::size_t>(actions)),
      observations_(static_cast<std::size_t>(states) * static_cast<std::size_t>(actions)),
      expected_reward_(static_cast<std::size_t>(states) * static_cast<std::size_t>(actions), 0.0),
      terminal_(static_cast<std::size_t>(states), 0) {}

void TabularModel::finish() {
  min_reward_ = std::numeric_limits<double>::infinity();
  max_reward_ = -std::numeric_limits<double>::infinity();
  std::fill(terminal_.begin(), terminal_.end(), 1);
  for (int a = 0; a < num_actions_; ++a) {
    for (int s = 0; s < num_states_; ++s) {
      double r = 0.0;
      for (const Transition& t : transitions(a, s)) r += t.probability * t.reward;
      expected_reward_[row(a, s)] = r;
      min_reward_ = std::min(min_reward_, r);
      max_reward_ = std::max(max_reward_, r);
      const auto& ts = transitions(a, s);
      const bool stays = ts.size() == 1 && ts[0].next == s && ts[0].reward == 0.0;
      if (!stays) terminal_[static_cast<std::size_t>(s)] = 0;
    }
  }
  if (num_actions_ == 0 || num_states_ == 0) min_reward_ = max_reward_ = 0.0;
}

Step TabularModel::step(StateId state, ActionId action, Rng& rng) const {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Step out;
  const auto& ts = transitions(action, state);
  double x = u(rng);
  const Transition* chosen = &ts.back();
  for (const Transition& t : ts) {
    x -= t.probability;
    if (x <= 0.0) {
      chosen = &t;
      break;
    }
  }
  out.next = chosen->next;
  out.reward = chosen->reward;
  const auto& os = observations(action, out.next);
  x = u(rng);
  out.observation = os.back().observation;
  for (const ObsProb& o : os) {
    x -= o.probability;
    if (x <= 0.0) {
      out.observation = o.observation;
      break;
    }
  }
  out.terminal = is_terminal(out.next);
  return out;
}

Expansion TabularModel::expand(const Belief& belief, ActionId action, Rng& /*rng*/) const {
  Expansion out;
  // Predicted next-state distribution, then split by observation.
  std::vector<Particle> predicted;
  for (const Particle& p : belief.particles()) {
    for (const Transition& t : transitions(action, p.state)) {
      predicted.push_back({t.next, p.weight * t.probability});
      out.reward += p.weight * t.probability * t.reward;
    }
  }
  Belief next(std::move(predicted));
  next.normalize();
  std::vector<Belief> by_obs(static_cast<std::size_t>(num_observations_));
  for (const Particle& p : next.particles()) {
    for (const ObsProb& o : observations(action, p.state)) {
      by_obs[static_cast<std::size_t>(o.observation)].add(p.state, p.weight * o.probability);
    }
  }
  for (int o = 0; o < num_observations_; ++o) {
    Belief& b = by_obs[static_cast<std::size_t>(o)];
    if (b.empty()) continue;
    const double mass = b.normalize();
    if (mass > 0.0) out.outcomes.push_back({o, mass, std::move(b)});
  }
  return out;
}

}  // namespace plr::pomdp
