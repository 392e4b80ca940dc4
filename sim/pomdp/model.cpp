#include "plr/pomdp/model.hpp"

#include <algorithm>
#include <map>

namespace plr::pomdp {

Expansion GenerativeModel::expand(const Belief& belief, ActionId action, Rng& rng) const {
  Expansion out;
  std::map<ObsId, Belief> by_observation;
  double total = 0.0;
  const int samples = std::max(1, samples_per_particle);
  for (const Particle& p : belief.particles()) {
    for (int k = 0; k < samples; ++k) {
      const double w = p.weight / samples;
      if (is_terminal(p.state)) {
        // A finished episode stays where it is and earns nothing.
        by_observation[0].add(p.state, w);
      } else {
        const Step s = step(p.state, action, rng);
        out.reward += w * s.reward;
        by_observation[s.observation].add(s.next, w);
      }
      total += w;
    }
  }
  if (total <= 0.0) return out;
  out.reward /= total;
  for (auto& [o, next] : by_observation) {
    const double mass = next.normalize();
    out.outcomes.push_back({o, mass / total, std::move(next)});
  }
  return out;
}

StateId sample_state(const Belief& belief, Rng& rng) {
  const auto& ps = belief.particles();
  std::uniform_real_distribution<double> u(0.0, belief.total_weight());
  double x = u(rng);
  for (const Particle& p : ps) {
    x -= p.weight;
    if (x <= 0.0) return p.state;
  }
  return ps.back().state;
}

Belief update_belief(const GenerativeModel& model, const Belief& belief, ActionId action,
                     ObsId observation, Rng& rng) {
  Expansion e = model.expand(belief, action, rng);
  for (Outcome& o : e.outcomes) {
    if (o.observation == observation) return std::move(o.next);
  }
  return {};
}

bool is_terminal(const GenerativeModel& model, const Belief& belief) {
  return std::all_of(belief.particles().begin(), belief.particles().end(),
                     [&model](const Particle& p) { return model.is_terminal(p.state); });
}

}  // namespace plr::pomdp
