#include "plr/pomdp/heuristics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace plr::pomdp {

double AlphaVectors::value(const Belief& belief) const {
  double best = -std::numeric_limits<double>::infinity();
  for (const auto& alpha : alphas_) {
    double v = 0.0;
    for (const Particle& p : belief.particles()) {
      v += p.weight * alpha[static_cast<std::size_t>(p.state)];
    }
    best = std::max(best, v);
  }
  return best;
}

AlphaVectors blind_lower_bound(const TabularModel& m, const BoundOptions& options) {
  const int S = m.num_states(), A = m.num_actions();
  const double g = m.discount();
  const double start = m.min_reward() / (1.0 - g);
  std::vector<std::vector<double>> alpha(static_cast<std::size_t>(A),
                                         std::vector<double>(static_cast<std::size_t>(S), start));
  // Gauss-Seidel sweeps: in place, still monotone from below.
  for (int it = 0; it < options.max_iterations; ++it) {
    double change = 0.0;
    for (int a = 0; a < A; ++a) {
      auto& v = alpha[static_cast<std::size_t>(a)];
      for (int s = 0; s < S; ++s) {
        double x = 0.0;
        for (const Transition& t : m.transitions(a, s)) {
          x += t.probability * (t.reward + g * v[static_cast<std::size_t>(t.next)]);
        }
        change = std::max(change, std::abs(x - v[static_cast<std::size_t>(s)]));
        v[static_cast<std::size_t>(s)] = x;
      }
    }
    if (change < options.tolerance) break;
  }
  return AlphaVectors("blind", std::move(alpha));
}

std::vector<double> mdp_values(const TabularModel& m, const BoundOptions& options) {
  const int S = m.num_states(), A = m.num_actions();
  const double g = m.discount();
  std::vector<double> v(static_cast<std::size_t>(S), m.max_reward() / (1.0 - g));
  for (int it = 0; it < options.max_iterations; ++it) {
    double change = 0.0;
    for (int s = 0; s < S; ++s) {
      double best = -std::numeric_limits<double>::infinity();
      for (int a = 0; a < A; ++a) {
        double x = 0.0;
        for (const Transition& t : m.transitions(a, s)) {
          x += t.probability * (t.reward + g * v[static_cast<std::size_t>(t.next)]);
        }
        best = std::max(best, x);
      }
      change = std::max(change, std::abs(best - v[static_cast<std::size_t>(s)]));
      v[static_cast<std::size_t>(s)] = best;
    }
    if (change < options.tolerance) break;
  }
  return v;
}

std::vector<ActionId> mdp_greedy_actions(const TabularModel& m, const std::vector<double>& v) {
  std::vector<ActionId> greedy(static_cast<std::size_t>(m.num_states()), 0);
  for (int s = 0; s < m.num_states(); ++s) {
    double best = -std::numeric_limits<double>::infinity();
    for (int a = 0; a < m.num_actions(); ++a) {
      double x = 0.0;
      for (const Transition& t : m.transitions(a, s)) {
        x += t.probability * (t.reward + m.discount() * v[static_cast<std::size_t>(t.next)]);
      }
      if (x > best) {
        best = x;
        greedy[static_cast<std::size_t>(s)] = a;
      }
    }
  }
  return greedy;
}

AlphaVectors fib_upper_bound(const TabularModel& m, const std::vector<double>& v,
                             const BoundOptions& options) {
  const int S = m.num_states(), A = m.num_actions(), O = m.num_observations();
  const double g = m.discount();
  // The QMDP vectors are an upper bound themselves; FIB tightens them.
  std::vector<std::vector<double>> alpha(static_cast<std::size_t>(A),
                                         std::vector<double>(static_cast<std::size_t>(S)));
  for (int a = 0; a < A; ++a) {
    for (int s = 0; s < S; ++s) {
      double x = 0.0;
      for (const Transition& t : m.transitions(a, s)) {
        x += t.probability * (t.reward + g * v[static_cast<std::size_t>(t.next)]);
      }
      alpha[static_cast<std::size_t>(a)][static_cast<std::size_t>(s)] = x;
    }
  }
  // alpha_a(s) = R(s,a) + g * sum_o max_a' sum_s' T(s'|s,a) O(o|a,s') alpha_a'(s')
  std::vector<double> per_obs(static_cast<std::size_t>(O) * static_cast<std::size_t>(A));
  std::vector<int> touched;
  for (int it = 0; it < options.max_iterations; ++it) {
    double change = 0.0;
    for (int a = 0; a < A; ++a) {
      for (int s = 0; s < S; ++s) {
        double r = 0.0;
        touched.clear();
        for (const Transition& t : m.transitions(a, s)) {
          r += t.probability * t.reward;
          for (const ObsProb& o : m.observations(a, t.next)) {
            double* row =
                &per_obs[static_cast<std::size_t>(o.observation) * static_cast<std::size_t>(A)];
            if (std::find(touched.begin(), touched.end(), o.observation) == touched.end()) {
              touched.push_back(o.observation);
              std::fill(row, row + A, 0.0);
            }
            const double w = t.probability * o.probability;
            for (int b = 0; b < A; ++b) {
              row[b] += w * alpha[static_cast<std::size_t>(b)][static_cast<std::size_t>(t.next)];
            }
          }
        }
        double future = 0.0;
        for (int o : touched) {
          const double* row = &per_obs[static_cast<std::size_t>(o) * static_cast<std::size_t>(A)];
          future += *std::max_element(row, row + A);
        }
        double& cell = alpha[static_cast<std::size_t>(a)][static_cast<std::size_t>(s)];
        // min(): iterates only ever tighten, so each stays an upper bound.
        const double x = std::min(cell, r + g * future);
        change = std::max(change, std::abs(x - cell));
        cell = x;
      }
    }
    if (change < options.tolerance) break;
  }
  return AlphaVectors("fib", std::move(alpha));
}

double MostLikelyStateValue::value(const Belief& belief) const {
  const Particle* best = nullptr;
  for (const Particle& p : belief.particles()) {
    if (!best || p.weight > best->weight) best = &p;
  }
  return best ? values_[static_cast<std::size_t>(best->state)] : 0.0;
}

double RolloutValue::value(const Belief& belief) const {
  if (belief.empty()) return 0.0;
  std::uniform_int_distribution<ActionId> act(0, model_.num_actions() - 1);
  double total = 0.0;
  for (int k = 0; k < rollouts_; ++k) {
    StateId s = sample_state(belief, rng_);
    double ret = 0.0, g = 1.0;
    for (int d = 0; d < depth_ && !model_.is_terminal(s); ++d) {
      const Step st = model_.step(s, act(rng_), rng_);
      ret += g * st.reward;
      g *= model_.discount();
      s = st.next;
    }
    total += ret;
  }
  return total / std::max(1, rollouts_);
}

TabularHeuristics make_tabular_heuristics(const TabularModel& model, const BoundOptions& options) {
  TabularHeuristics h;
  std::vector<double> mdp = mdp_values(model, options);
  h.upper = std::make_unique<AlphaVectors>(fib_upper_bound(model, mdp, options));
  h.lower = std::make_unique<AlphaVectors>(blind_lower_bound(model, options));
  h.mdp_greedy = mdp_greedy_actions(model, mdp);
  h.most_likely = std::make_unique<MostLikelyStateValue>(std::move(mdp));
  return h;
}

}  // namespace plr::pomdp
