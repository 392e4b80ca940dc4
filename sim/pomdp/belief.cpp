#include "plr/pomdp/belief.hpp"

#include <algorithm>
#include <cmath>

namespace plr::pomdp {

Belief::Belief(std::vector<Particle> particles) : particles_(std::move(particles)) {}

void Belief::add(StateId state, double weight) {
  particles_.push_back({state, weight});
}

double Belief::normalize() {
  std::sort(particles_.begin(), particles_.end(),
            [](const Particle& a, const Particle& b) { return a.state < b.state; });
  std::size_t out = 0;
  for (std::size_t i = 0; i < particles_.size(); ++i) {
    if (out > 0 && particles_[out - 1].state == particles_[i].state) {
      particles_[out - 1].weight += particles_[i].weight;
    } else {
      particles_[out++] = particles_[i];
    }
  }
  particles_.resize(out);
  std::erase_if(particles_, [](const Particle& p) { return !(p.weight > 0.0); });
  const double total = total_weight();
  if (total > 0.0) {
    for (Particle& p : particles_) p.weight /= total;
  }
  return total;
}

double Belief::total_weight() const {
  double total = 0.0;
  for (const Particle& p : particles_) total += p.weight;
  return total;
}

double Belief::probability(StateId state) const {
  const auto it = std::lower_bound(particles_.begin(), particles_.end(), state,
                                   [](const Particle& p, StateId s) { return p.state < s; });
  return it != particles_.end() && it->state == state ? it->weight : 0.0;
}

std::uint64_t Belief::signature(double resolution) const {
  // FNV-1a over (state, rounded weight) pairs.
  std::uint64_t h = 1469598103934665603ull;
  const auto mix = [&h](std::uint64_t v) {
    for (int i = 0; i < 8; ++i) {
      h ^= (v >> (8 * i)) & 0xffu;
      h *= 1099511628211ull;
    }
  };
  for (const Particle& p : particles_) {
    const auto q = static_cast<std::int64_t>(std::llround(p.weight / resolution));
    if (q == 0) continue;
    mix(static_cast<std::uint64_t>(p.state));
    mix(static_cast<std::uint64_t>(q));
  }
  return h;
}

bool Belief::approx_equal(const Belief& other, double resolution) const {
  std::size_t i = 0, j = 0;
  const auto& a = particles_;
  const auto& b = other.particles_;
  // Particles that round to zero are ignored on both sides, as in signature().
  const auto skip = [resolution](const std::vector<Particle>& v, std::size_t& k) {
    while (k < v.size() && std::llround(v[k].weight / resolution) == 0) ++k;
  };
  for (;;) {
    skip(a, i);
    skip(b, j);
    if (i == a.size() || j == b.size()) return i == a.size() && j == b.size();
    if (a[i].state != b[j].state ||
        std::llround(a[i].weight / resolution) != std::llround(b[j].weight / resolution)) {
      return false;
    }
    ++i;
    ++j;
  }
}

}  // namespace plr::pomdp
