// What the online evaluation needs from a solver: think from the current
// belief within a budget, then hear what happened.
#pragma once

#include <cstdint>
#include <limits>
#include <string>

#include "plr/pomdp/belief.hpp"

namespace plr::pomdp {

// A search stops at whichever limit comes first.
struct Budget {
  double seconds = std::numeric_limits<double>::infinity();
  std::uint64_t iterations = std::numeric_limits<std::uint64_t>::max();  // trials or simulations
};

struct PlanStats {
  std::uint64_t iterations = 0;  // trials (POMHDP) or simulations (POMCP), this call
  std::size_t nodes = 0;         // belief nodes held after the call
  std::size_t memory_bytes = 0;  // approximate memory held by the search
  double seconds = 0.0;
  // Bounds on the root's value; POMCP has none and reports its value estimate as both.
  double lower = 0.0, upper = 0.0;
};

class OnlinePlanner {
 public:
  virtual ~OnlinePlanner() = default;
  virtual std::string name() const = 0;
  // Starts an episode from `belief`, dropping every search result.
  virtual void reset(const Belief& belief) = 0;
  virtual ActionId plan(const Budget& budget) = 0;
  // The action was taken and `observation` seen; `next` is the updated belief.
  virtual void advance(ActionId action, ObsId observation, const Belief& next) = 0;
  virtual const PlanStats& last_stats() const = 0;
};

}  // namespace plr::pomdp
