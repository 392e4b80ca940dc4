// Experience graphs (Phillips, Cohen, Chitta, Likhachev 2012) for the joint
// lattice: the robot makes the same motions hundreds of times a trailer (to a
// pre-grasp, to the drop-off over the nose, home), so the paths of earlier
// queries are kept and the next search is pulled toward them.
//
// ExperienceStore holds the last paths of a mode (bounded, oldest dropped).
// ExperienceGraph is their nodes for one query: every stored waypoint with
// the query's unplanned joints, and h_E, the cost to the goal over the graph
// where moving along a stored path costs its time and anything else costs
// w_E times the ordinary heuristic:
//
//   h_E(s) = min( w_E h(s, goal),  min_e  w_E h(s, e) + h_E(e) ).
//
// The lattice search adds, from a state, a direct move to the node its h_E
// goes through, and, from a node, moves along its stored path (to the next
// node, and a shortcut to the node of least h_E the path reaches while its
// segments are free). Every such move is collision-checked against the
// query's world like any lattice edge, so a path a box now blocks is not
// followed past the box. h_E <= w_E h, so weighted A* at ε on it returns a
// path within ε w_E of the optimal lattice path (Phillips et al., Theorem 1).
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <vector>

#include "plr/planning/plan_query.hpp"

namespace plr::planning {

class ExperienceStore {
 public:
  explicit ExperienceStore(std::size_t max_paths) : max_paths_(max_paths) {}

  // Keeps `path` (start first, at least two waypoints); drops the oldest
  // path when more than max_paths are kept.
  void add(std::vector<JointVector> path);
  void clear() { paths_.clear(); }
  const std::deque<std::vector<JointVector>>& paths() const { return paths_; }

 private:
  std::size_t max_paths_;
  std::deque<std::vector<JointVector>> paths_;
};

class ExperienceGraph {
 public:
  struct Node {
    JointVector q;
    std::int32_t path = 0;   // index in the store
    std::int32_t index = 0;  // waypoint in that path
    double h = 0.0;          // h_E
  };
  // pair_time(a, b): the heuristic between two configurations (a lower
  // bound on the motion's time); to_goal(q): the heuristic to the goal.
  ExperienceGraph(const ExperienceStore& store, const JointVector& start,
                  const std::vector<int>& planned, double weight,
                  const std::function<double(const JointVector&, const JointVector&)>& pair_time,
                  const std::function<double(const JointVector&)>& to_goal);

  bool empty() const { return nodes_.empty(); }
  double weight() const { return weight_; }
  const std::vector<Node>& nodes() const { return nodes_; }
  // Node id of the waypoint `index` of `path`, or -1 past either end.
  std::int32_t node_at(std::int32_t path, std::int32_t index) const;
  // Whether the segment between a node and the next one on its path is
  // free (-1 unknown); kept for the query.
  std::int8_t& segment_free(std::int32_t node) { return segment_free_[node]; }

  // h_E of a configuration whose ordinary heuristic to the goal is `h_goal`,
  // and the node it goes through (-1: straight to the goal).
  struct Estimate {
    double h = 0.0;
    std::int32_t via = -1;
  };
  Estimate estimate(const JointVector& q, double h_goal) const;

 private:
  double weight_;
  std::function<double(const JointVector&, const JointVector&)> pair_time_;
  std::vector<Node> nodes_;
  std::vector<std::int32_t> first_;  // first node of each path
  std::vector<std::int8_t> segment_free_;
};

}  // namespace plr::planning
