// POMHDP: forward-search dynamic programming over an AND-OR graph of beliefs
// (belief nodes choose an action; action nodes branch on observations), with
// an admissible anchor heuristic and inadmissible ones scheduled as in MHA*.
// See docs/pomdp.md for what was reconstructed and why.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <unordered_map>
#include <vector>

#include "plr/pomdp/heuristics.hpp"
#include "plr/pomdp/model.hpp"
#include "plr/pomdp/planner.hpp"
#include "plr/pomdp/policy_tree.hpp"

namespace plr::pomdp {

struct PomhdpOptions {
  // Inflation of the inadmissible heuristics (cost-to-go scaled by epsilon1).
  double epsilon1 = 10.0;
  // A search may take an inadmissible heuristic's action only while its
  // anchor cost is within epsilon2 times the anchor's best.
  double epsilon2 = 10.0;
  // Both factors move halfway to 1 every this many trials (anytime).
  int epsilon_period = 64;
  // Stop when the root's upper and lower bounds are this close.
  double target_gap = 1e-3;
  // A trial ends where a belief's gap is below its share of the root's
  // target, gamma^-depth * max(target_gap, trial_gap_fraction * root gap)
  // (HSVI's rule; a fraction of the root's current gap rather than the final
  // target keeps early trials from going ever deeper). 0: the target alone.
  double trial_gap_fraction = 0.0;
  // Trial depth limit; 0 derives it from the discount and the value range
  // (100 for goal-directed models).
  int max_depth = 0;
  // Beliefs equal after rounding their weights to this share one node.
  double belief_resolution = 1e-9;
  // Online (plan()): also stop once the best action is settled, its lower
  // bound at most settle_tolerance below every other action's upper bound
  // (so it loses at most that much against the optimum); negative: never.
  double settle_tolerance = 1e-2;
  // Drop an action at a belief once its upper bound is below the belief's
  // lower bound (it cannot be optimal). Needs true bounds: turn it off when
  // the lower heuristic is only an estimate.
  bool prune_actions = true;
  // Limits of the graph. At either, the older half of the nodes (by the
  // last trial through them) become unvisited branches again, their bounds
  // kept, and the search goes on; with `reclaim` off it stops there.
  std::size_t max_nodes = 4'000'000;
  std::size_t max_memory_bytes = std::size_t{1} << 30;
  bool reclaim = true;
  // reset() to a belief the graph holds keeps the graph and starts from that
  // node (online episodes from the same initial belief start warm); the
  // graph then keeps what the episode's first belief reaches, within the
  // limits above. Off: reset() starts an empty graph.
  bool warm_start = false;
  std::uint64_t seed = 1;
};

class Pomhdp final : public OnlinePlanner {
 public:
  // `upper` must be admissible (never below the optimal value) and `lower` a
  // lower bound (or an estimate of one for simulated models). The heuristics
  // must outlive the solver.
  Pomhdp(const GenerativeModel& model, const Heuristic& upper, const Heuristic& lower,
         std::vector<const Heuristic*> inadmissible, PomhdpOptions options = {});

  std::string name() const override { return "POMHDP"; }
  // Starts from `belief`: an empty graph, or with warm_start the node the
  // graph has for it.
  void reset(const Belief& belief) override;
  // Runs trials until the budget ends or the bounds meet, then returns the
  // root action with the best lower bound.
  ActionId plan(const Budget& budget) override;
  // Re-roots on the child and frees what it cannot reach; starts afresh from
  // `next` if the child was never generated.
  void advance(ActionId action, ObsId observation, const Belief& next) override;
  const PlanStats& last_stats() const override { return stats_; }

  // Runs trials until the budget ends or the bounds meet (offline use).
  PlanStats solve(const Budget& budget);
  double lower() const { return nodes_[root_].lower; }
  double upper() const { return nodes_[root_].upper; }
  ActionId best_action();
  // The policy from the root up to `horizon` actions deep: the best-lower-bound
  // action at each belief, a child per possible observation. Expands beliefs
  // the trials did not reach, unless `expand_unvisited` is false: then a
  // branch ends at a belief no trial expanded (its policy is left to whoever
  // runs the tree), which costs no model calls.
  PolicyTree policy_tree(int horizon, bool expand_unvisited = true);

  // Belief nodes (visited beliefs); unvisited children are not nodes.
  std::size_t num_nodes() const { return nodes_.size(); }
  std::size_t memory_bytes() const { return bytes_; }
  // How many times the graph hit a limit and gave back its older half.
  std::uint64_t reclaims() const { return reclaims_; }
  std::uint64_t total_trials() const { return total_trials_; }
  double epsilon1() const { return epsilon1_; }
  double epsilon2() const { return epsilon2_; }

 private:
  // An observation branch of an action. Until a trial first enters it, the
  // child is not a node: the branch keeps its bounds (and the raw
  // inadmissible estimates, in Node::branch_h) and no belief; the belief is
  // made again from the parent when a trial goes there.
  static constexpr std::uint32_t kUnvisited = 0xffffffffu;
  static constexpr std::uint32_t kTerminal = 0xfffffffeu;  // value 0, never a node
  struct Branch {
    double probability = 0.0;
    double upper = 0.0, lower = 0.0;  // the child's bounds while unvisited
    ObsId observation = 0;
    std::uint32_t child = kUnvisited;  // a node id, kUnvisited or kTerminal
  };
  struct Edge {
    double reward = 0.0;
    std::uint32_t first = 0;  // its branches are Node::branches[first, first + count)
    std::uint32_t count = 0;
    bool pruned = false;  // its upper bound fell below the belief's lower bound
  };
  struct Node {
    Belief belief;
    std::uint64_t signature = 0;
    std::uint64_t stamp = 0;  // the last trial through this node
    bool terminal = false;
    bool expanded = false;
    double upper = 0.0, lower = 0.0;
    // One value per inadmissible heuristic: the raw estimate at a leaf, the
    // backed-up (inflated) value once expanded.
    std::vector<double> h;
    std::vector<Edge> edges;  // by action, once expanded
    std::vector<Branch> branches;
    std::vector<double> branch_h;  // [branch * h.size() + i], for unvisited branches
  };

  // The node of a belief if there is one, else kUnvisited; `key` gets the
  // index key the belief has or would get.
  std::uint32_t find(const Belief& belief, std::uint64_t& key) const;
  // The node of a belief, made if needed; `bounds` (upper, lower, then the
  // inadmissible estimates) saves evaluating the heuristics again.
  std::uint32_t node_for(Belief belief, const double* bounds = nullptr);
  void expand(std::uint32_t id);
  // Makes the child of branch `k` (of action `a`) a node and returns it.
  std::uint32_t visit(std::uint32_t id, ActionId a, std::size_t k);
  Rng expansion_rng(std::uint64_t signature, ActionId a) const;
  void backup(std::uint32_t id);
  double branch_upper(const Branch& b) const {
    return b.child < kTerminal ? nodes_[b.child].upper : b.upper;
  }
  double branch_lower(const Branch& b) const {
    return b.child < kTerminal ? nodes_[b.child].lower : b.lower;
  }
  double q_upper(const Node& n, const Edge& e) const;
  double q_lower(const Node& n, const Edge& e) const;
  double q_h(const Node& n, const Edge& e, std::size_t i) const;
  double leaf_h(const Node& n, std::size_t i) const;
  double inflate(double h) const { return v_max_ - epsilon1_ * (v_max_ - h); }
  ActionId choose_action(const Node& n, std::size_t heuristic) const;
  void trial(std::size_t heuristic, std::chrono::steady_clock::time_point deadline);
  PlanStats run(const Budget& budget, bool until_settled);
  bool settled() const;
  bool room_left() const {
    return nodes_.size() < options_.max_nodes && bytes_ < options_.max_memory_bytes;
  }
  // Drops what neither the root nor the home node reaches.
  void compact();
  // Turns the older half of the nodes back into unvisited branches.
  void reclaim();
  std::size_t node_bytes(const Node& n) const;

  const GenerativeModel& model_;
  const Heuristic& upper_;
  const Heuristic& lower_;
  std::vector<const Heuristic*> inadmissible_;
  PomhdpOptions options_;
  double gamma_, v_max_;
  int max_depth_;
  std::vector<Node> nodes_;
  // Belief signature -> node; a (rare) collision of different beliefs moves
  // to the next free key, and the node remembers the key it got.
  std::unordered_map<std::uint64_t, std::uint32_t> index_;
  // Unreachable nodes are dropped only when the graph has doubled since the
  // last compaction: copying it at every step would cost more than the search.
  std::size_t compact_at_ = 0;
  std::size_t bytes_ = 0;  // held by nodes_ and index_, kept as they grow
  std::uint32_t root_ = 0;
  // The node of the belief reset() last started from (kept by compaction for
  // warm starts); kUnvisited without warm_start.
  std::uint32_t home_ = kUnvisited;
  std::uint64_t reclaims_ = 0;
  double epsilon1_, epsilon2_;
  std::uint64_t total_trials_ = 0;
  std::size_t next_heuristic_ = 0;
  std::vector<std::uint32_t> path_;
  PlanStats stats_;
};

}  // namespace plr::pomdp
