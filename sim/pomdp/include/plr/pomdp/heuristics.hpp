// Value estimates of beliefs. Bounds from a tabular model: a lower bound from
// blind policies (one fixed action forever), an upper bound from the fast
// informed bound (FIB); and two inadmissible estimates for POMHDP's extra
// searches. Generative models get rollout and constant estimates.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "plr/pomdp/model.hpp"
#include "plr/pomdp/tabular_model.hpp"

namespace plr::pomdp {

class Heuristic {
 public:
  virtual ~Heuristic() = default;
  virtual double value(const Belief& belief) const = 0;
  virtual std::string name() const = 0;
};

// max over vectors of sum_s b(s) alpha(s).
class AlphaVectors final : public Heuristic {
 public:
  AlphaVectors(std::string name, std::vector<std::vector<double>> alphas)
      : name_(std::move(name)), alphas_(std::move(alphas)) {}
  double value(const Belief& belief) const override;
  std::string name() const override { return name_; }
  const std::vector<std::vector<double>>& alphas() const { return alphas_; }

 private:
  std::string name_;
  std::vector<std::vector<double>> alphas_;
};

// Value iteration stops when no entry moves more than `tolerance`, or after
// `max_iterations`; every iterate is a valid bound (they start from the
// trivial bounds and move monotonically), so stopping early stays safe.
struct BoundOptions {
  double tolerance = 1e-6;
  int max_iterations = 5000;
};

// Needs a discount below 1.
AlphaVectors blind_lower_bound(const TabularModel& model, const BoundOptions& options = {});
// The fully observable optimum V_MDP(s).
std::vector<double> mdp_values(const TabularModel& model, const BoundOptions& options = {});
// The greedy action of every state in the fully observable MDP whose values
// are `mdp` (mdp_values()): argmax_a R(s, a) + g * sum_s' T(s' | s, a) V(s').
std::vector<ActionId> mdp_greedy_actions(const TabularModel& model, const std::vector<double>& mdp);
// Starts from the QMDP vectors built on `mdp` (mdp_values()) and tightens them.
AlphaVectors fib_upper_bound(const TabularModel& model, const std::vector<double>& mdp,
                             const BoundOptions& options = {});

// V_MDP of the most likely state: optimistic about what is not known yet,
// neither an upper nor a lower bound.
class MostLikelyStateValue final : public Heuristic {
 public:
  explicit MostLikelyStateValue(std::vector<double> values) : values_(std::move(values)) {}
  double value(const Belief& belief) const override;
  std::string name() const override { return "mls-mdp"; }

 private:
  std::vector<double> values_;
};

// A constant (for example max_reward / (1 - discount), or 0 for costs).
class ConstantValue final : public Heuristic {
 public:
  ConstantValue(std::string name, double v) : name_(std::move(name)), value_(v) {}
  double value(const Belief&) const override { return value_; }
  std::string name() const override { return name_; }

 private:
  std::string name_;
  double value_;
};

// The mean discounted return of uniformly random actions from particles of
// the belief, `depth` steps deep: an estimate, not a bound.
class RolloutValue final : public Heuristic {
 public:
  RolloutValue(const GenerativeModel& model, int rollouts, int depth, std::uint64_t seed)
      : model_(model), rollouts_(rollouts), depth_(depth), rng_(seed) {}
  double value(const Belief& belief) const override;
  std::string name() const override { return "rollout"; }

 private:
  const GenerativeModel& model_;
  int rollouts_, depth_;
  mutable Rng rng_;
};

// The set POMHDP uses on a tabular model: anchor FIB (admissible), lower
// bound blind, inadmissible most-likely-state MDP value and the blind bound.
struct TabularHeuristics {
  std::unique_ptr<AlphaVectors> upper, lower;
  std::unique_ptr<MostLikelyStateValue> most_likely;
  std::vector<ActionId> mdp_greedy;  // the MDP's greedy action per state (rollouts)
  std::vector<const Heuristic*> inadmissible() const { return {most_likely.get(), lower.get()}; }
};
TabularHeuristics make_tabular_heuristics(const TabularModel& model,
                                          const BoundOptions& options = {});

}  // namespace plr::pomdp
