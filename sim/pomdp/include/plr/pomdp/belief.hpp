// Beliefs as weighted particles: a state handle and a weight per particle.
// For tabular models every state appears once and the weights are the exact
// probabilities; for simulated models a particle is a sampled world.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace plr::pomdp {

using StateId = std::int32_t;
using ActionId = std::int32_t;
using ObsId = std::int32_t;

struct Particle {
  StateId state = 0;
  double weight = 0.0;
};

class Belief {
 public:
  Belief() = default;
  explicit Belief(std::vector<Particle> particles);

  // Appends a particle; normalize() merges particles of one state.
  void add(StateId state, double weight);
  // Sorts by state, merges duplicates, drops zero weights and scales the
  // weights to sum to one. Returns the weight before scaling.
  double normalize();

  const std::vector<Particle>& particles() const { return particles_; }
  bool empty() const { return particles_.empty(); }
  std::size_t size() const { return particles_.size(); }
  double total_weight() const;
  // Probability of one state (0 when absent); needs a normalized belief.
  double probability(StateId state) const;

  // A hash of the normalized belief with weights rounded to `resolution`:
  // equal beliefs (up to rounding) share one search node.
  std::uint64_t signature(double resolution) const;
  bool approx_equal(const Belief& other, double resolution) const;

 private:
  std::vector<Particle> particles_;
};

}  // namespace plr::pomdp
