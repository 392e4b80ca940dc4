// Moving AI grid benchmarks (movingai.com/benchmarks) as a search graph:
// octile moves, diagonals only when both side cells are free (no corner
// cutting), costs 1 and sqrt(2); '.', 'G' and 'S' are passable.
#pragma once

#include <string>
#include <vector>

#include "plr/search/graph.hpp"

namespace plr::search {

struct GridMap {
  int width = 0;
  int height = 0;
  std::vector<unsigned char> passable;  // row-major, y * width + x
  bool free(int x, int y) const {
    return x >= 0 && y >= 0 && x < width && y < height &&
           passable[static_cast<std::size_t>(y) * width + x] != 0;
  }
};

struct GridQuery {
  int start_x = 0, start_y = 0, goal_x = 0, goal_y = 0;
  double optimal = 0.0;
};

// Throw std::runtime_error "<file>: <cause>" on unreadable or malformed input.
GridMap load_grid_map(const std::string& path);
std::vector<GridQuery> load_scenario(const std::string& path);

class GridGraph final : public Graph {
 public:
  explicit GridGraph(const GridMap& map) : map_(map) {}
  void set_goal(int x, int y) { goal_ = id(x, y); }
  StateId id(int x, int y) const { return y * map_.width + x; }
  void successors(StateId s, std::vector<Successor>& out) override;
  bool is_goal(StateId s) override { return s == goal_; }

 private:
  const GridMap& map_;
  StateId goal_ = kNoState;
};

class OctileHeuristic final : public Heuristic {
 public:
  explicit OctileHeuristic(const GridMap& map) : width_(map.width) {}
  void set_goal(int x, int y) { gx_ = x, gy_ = y; }
  double estimate(StateId s) override;

 private:
  int width_;
  int gx_ = 0, gy_ = 0;
};

}  // namespace plr::search
