// Graph and heuristic interfaces of the search core.
//
// A graph names its states by dense integer ids that it hands out as it
// creates states (lazily, usually from a hash of the state's coordinates);
// the search only ever sees ids. Search, graph and heuristic are separate, so
// the same searches run on the robot lattice and on Moving AI grids.
#pragma once

#include <cstdint>
#include <vector>

namespace plr::search {

using StateId = std::int32_t;
inline constexpr StateId kNoState = -1;

struct Successor {
  StateId id = kNoState;
  double cost = 0.0;  // > 0
};

class Graph {
 public:
  virtual ~Graph() = default;
  // Appends the successors of `s` to `out` (the caller clears it).
  virtual void successors(StateId s, std::vector<Successor>& out) = 0;
  virtual bool is_goal(StateId s) = 0;
};

class Heuristic {
 public:
  virtual ~Heuristic() = default;
  // Estimate of the cost from `s` to a goal; admissible for ε = 1 to be optimal.
  virtual double estimate(StateId s) = 0;
};

// Turns A* into Dijkstra.
class ZeroHeuristic final : public Heuristic {
 public:
  double estimate(StateId) override { return 0.0; }
};

}  // namespace plr::search
