// The robot's search graphs for the ARA* planner.
//
// JointLattice (M1, M2, M3, M5, M6): a uniform lattice over a mode's planned
// joints, anchored at the start configuration; the other joints stay at their
// start values. States are created lazily and hashed by their integer lattice
// coordinates. Successors are the mode's motion primitives plus adaptive
// ones that jump straight to the goal: through the arm IK for a plate pose
// goal, directly for a joint goal, once the state is near enough. Edge cost is
// the primitive's execution time under velocity limits (slowest joint).
// In escape mode (M6) edges are not collision-checked (the robot starts in
// contact) and every collision-free state is a goal; run it with Dijkstra.
// Given stored paths (experience.hpp), the heuristic is h_E and the stored
// paths' nodes and segments join the successors.
//
// LineLattice (M4): the plate moves along the straight line from its start
// position to the goal (yaw interpolated). States are progress steps along
// the line with IK configurations chosen continuously; edges skip ahead by
// the mode's steps when the joint-space motion stays within line_tolerance
// of the line.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <unordered_map>
#include <variant>
#include <vector>

#include "experience.hpp"
#include "plr/planning/lattice_config.hpp"
#include "plr/search/graph.hpp"

namespace plr::planning {

using Goal = std::variant<std::monostate, JointGoal, PoseGoal>;

class JointLattice final : public search::Graph {
 public:
  // `experience` (may be null or empty: none) is read during construction
  // only; `experience_weight` is w_E.
  JointLattice(const ModeLattice& lattice, const sim::CollisionChecker& checker,
               const sim::JointVector& start, const Goal& goal, bool escape,
               const ExperienceStore* experience = nullptr, double experience_weight = 1.0);

  search::StateId start() const { return 0; }
  const sim::JointVector& config(search::StateId s) const {
    return states_[static_cast<std::size_t>(s)].q;
  }
  void successors(search::StateId s, std::vector<search::Successor>& out) override;
  bool is_goal(search::StateId s) override;

  // Execution-time lower bound to the goal (the heuristic); with
  // experience, h_E.
  double heuristic(search::StateId s) const;
  // The configurations of a path of state ids: a shortcut along a stored
  // path is unfolded into the stored waypoints it passes.
  std::vector<sim::JointVector> path_configs(const std::vector<search::StateId>& ids) const;
  // Expansions that followed a stored path or jumped onto one.
  std::size_t experience_edges() const { return experience_edges_; }

 private:
  using Key = std::array<std::int32_t, sim::kNumJoints>;
  struct KeyHash {
    std::size_t operator()(const Key& k) const {
      std::uint64_t h = 1469598103934665603ull;
      for (std::int32_t v : k) h = (h ^ static_cast<std::uint32_t>(v)) * 1099511628211ull;
      return static_cast<std::size_t>(h);
    }
  };
  struct State {
    sim::JointVector q;
    Key key{};
    Eigen::Vector3d plate = Eigen::Vector3d::Zero();
    double yaw = 0.0;
    std::int8_t valid = -1;  // -1 unknown
    bool goal = false;
    bool snapped = false;      // reached by a snap primitive (not on the lattice)
    bool off_lattice = false;  // reached by a Cartesian step (M6)
    std::int32_t node = -1;    // the experience node it is
    std::int32_t via = -1;     // the experience node its h_E goes through
    double h_e = 0.0;
  };

  search::StateId intern(const Key& key, const sim::JointVector& q, bool off_lattice = false);
  Key off_lattice_key(const sim::JointVector& q) const;
  search::StateId add_goal_state(const sim::JointVector& q);
  bool valid(search::StateId s);
  bool within_goal(const State& st) const;
  double plain_heuristic(const State& st) const;
  static Key node_key(std::int32_t node);
  search::StateId node_state(std::int32_t node);
  void experience_successors(const State& from, std::vector<search::Successor>& out);
  double time(const sim::JointVector& a, const sim::JointVector& b) const;
  void fill_plate(State& st) const;

  const ModeLattice& lattice_;
  const sim::CollisionChecker& checker_;
  const sim::RobotModel& robot_;
  Goal goal_;
  bool escape_;
  sim::JointVector start_;
  sim::JointVector joint_goal_ = sim::JointVector::Zero();  // full config, for joint goals
  std::vector<State> states_;
  std::unordered_map<Key, search::StateId, KeyHash> index_;
  std::vector<search::StateId> snapped_;
  std::unique_ptr<ExperienceGraph> experience_;
  std::size_t experience_edges_ = 0;
};

class LineLattice final : public search::Graph {
 public:
  LineLattice(const ModeLattice& lattice, const sim::CollisionChecker& checker,
              const sim::JointVector& start, const PoseGoal& goal);

  search::StateId start() const { return 0; }
  const sim::JointVector& config(search::StateId s) const {
    return configs_[static_cast<std::size_t>(s)];
  }
  void successors(search::StateId s, std::vector<search::Successor>& out) override;
  bool is_goal(search::StateId s) override { return s == count_ - 1; }
  double heuristic(search::StateId s) const;
  // IK failed or jumped between branches at this progress index (or -1).
  int broken_at() const { return broken_at_; }

 private:
  sim::PlateTarget target_at(int i) const;
  bool ensure(int i);  // IK configurations up to index i
  bool stays_on_line(int i, int j) const;

  const ModeLattice& lattice_;
  const sim::CollisionChecker& checker_;
  const sim::RobotModel& robot_;
  sim::PlateTarget from_, to_;
  int count_ = 2;
  std::vector<sim::JointVector> configs_;
  std::vector<std::int8_t> valid_;
  int broken_at_ = -1;
};

// Adapts a graph's heuristic member to the search's Heuristic interface.
template <class G>
class GraphHeuristic final : public search::Heuristic {
 public:
  explicit GraphHeuristic(const G& g) : g_(g) {}
  double estimate(search::StateId s) override { return g_.heuristic(s); }

 private:
  const G& g_;
};

}  // namespace plr::planning
