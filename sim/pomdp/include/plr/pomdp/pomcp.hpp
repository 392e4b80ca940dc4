// POMCP (Silver and Veness, NIPS 2010): Monte-Carlo tree search over
// action-observation histories with UCB1 at belief nodes and rollouts below
// the tree (uniformly random, or a given state-based policy). Here the root's states are drawn from
// the belief the caller keeps (exact for tabular models), so it never runs out of particles; the
// subtree of the taken branch is kept between steps.
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "plr/pomdp/model.hpp"
#include "plr/pomdp/planner.hpp"

namespace plr::pomdp {

struct PomcpOptions {
  // UCB1 exploration constant; 0: the spread of the returns simulated so far
  // (highest minus lowest), as Silver and Veness set it.
  double exploration = 0.0;
  // Simulation depth; 0 derives it from the discount (gamma^depth < 0.01),
  // 100 for goal-directed models.
  int max_depth = 0;
  std::size_t max_nodes = 4'000'000;
  // The rollout policy below the tree, on the sampled state; empty:
  // uniformly random actions. (Silver and Veness gave RockSample
  // domain-specific preferred actions; rollout_policy_from() below is a
  // generic stand-in.)
  std::function<ActionId(StateId, Rng&)> rollout_policy;
  // reset() to the belief of the previous reset() keeps the tree (episodes
  // from the same initial belief start warm); advance() then moves down the
  // tree without dropping the rest, until it holds half of max_nodes.
  bool warm_start = false;
  std::uint64_t seed = 1;
};

// A rollout policy that takes, in the sampled state, the action with the best
// value in the fully observable MDP (`greedy[state]`, from
// mdp_greedy_actions()): the MDP's greedy action on a sampled state.
std::function<ActionId(StateId, Rng&)> rollout_policy_from(std::vector<ActionId> greedy);

class Pomcp final : public OnlinePlanner {
 public:
  Pomcp(const GenerativeModel& model, PomcpOptions options = {});

  std::string name() const override { return "POMCP"; }
  void reset(const Belief& belief) override;
  ActionId plan(const Budget& budget) override;
  void advance(ActionId action, ObsId observation, const Belief& next) override;
  const PlanStats& last_stats() const override { return stats_; }

  std::size_t num_nodes() const { return nodes_.size(); }
  // Visit count and mean return of a root action (for tests).
  std::uint32_t root_visits(ActionId a) const;
  double root_value(ActionId a) const;

 private:
  struct ActionStats {
    std::uint32_t visits = 0;
    double value = 0.0;
    std::vector<std::pair<ObsId, std::uint32_t>> children;  // observation -> node
  };
  struct Node {
    std::uint32_t visits = 0;
    std::vector<ActionStats> actions;  // empty until the node is first simulated through
  };

  double simulate(StateId s, std::uint32_t node, int depth);
  double rollout(StateId s, int depth);
  std::uint32_t child(std::uint32_t node, ActionId a, ObsId o);
  void keep_subtree(std::uint32_t new_root);
  void count_bytes();

  const GenerativeModel& model_;
  PomcpOptions options_;
  Rng rng_;
  double gamma_, c_;
  double return_lo_ = 0.0, return_hi_ = 0.0;  // returns simulated since reset()
  bool have_returns_ = false;
  int max_depth_;
  Belief belief_;
  Belief home_belief_;         // the belief of the last reset() that kept or began a tree
  bool at_home_tree_ = false;  // root_'s tree is still the one begun at home_belief_
  std::uint32_t home_ = 0;
  std::vector<Node> nodes_;
  std::uint32_t root_ = 0;
  std::size_t bytes_ = 0;  // held by the tree, kept as it grows
  PlanStats stats_;
};

}  // namespace plr::pomdp
