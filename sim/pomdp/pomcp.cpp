#include "plr/pomdp/pomcp.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

namespace plr::pomdp {
namespace {
constexpr std::uint32_t kNoNode = std::numeric_limits<std::uint32_t>::max();
}  // namespace

Pomcp::Pomcp(const GenerativeModel& model, PomcpOptions options)
    : model_(model), options_(options), rng_(options.seed), gamma_(model.discount()) {
  c_ = options.exploration > 0.0 ? options.exploration
                                 : std::max(1e-6, model.max_reward() - model.min_reward());
  if (options.max_depth > 0) {
    max_depth_ = options.max_depth;
  } else if (gamma_ < 1.0) {
    max_depth_ = static_cast<int>(std::ceil(std::log(0.01) / std::log(std::max(1e-9, gamma_))));
  } else {
    max_depth_ = 100;
  }
  reset(model.initial_belief());
}

void Pomcp::reset(const Belief& belief) {
  belief_ = belief;
  if (options_.warm_start && at_home_tree_ && belief.approx_equal(home_belief_, 1e-9)) {
    root_ = home_;
    return;
  }
  nodes_.assign(1, Node{});
  bytes_ = sizeof(Node);
  root_ = home_ = 0;
  home_belief_ = belief;
  at_home_tree_ = options_.warm_start;
  have_returns_ = false;
}

std::function<ActionId(StateId, Rng&)> rollout_policy_from(std::vector<ActionId> greedy) {
  return
      [greedy = std::move(greedy)](StateId s, Rng&) { return greedy[static_cast<std::size_t>(s)]; };
}

std::uint32_t Pomcp::child(std::uint32_t node, ActionId a, ObsId o) {
  auto& ch = nodes_[node].actions[static_cast<std::size_t>(a)].children;
  for (const auto& [obs, id] : ch) {
    if (obs == o) return id;
  }
  if (nodes_.size() >= options_.max_nodes) return kNoNode;
  const auto id = static_cast<std::uint32_t>(nodes_.size());
  nodes_.emplace_back();
  auto& children = nodes_[node].actions[static_cast<std::size_t>(a)].children;
  bytes_ -= children.capacity() * sizeof(children[0]);
  children.emplace_back(o, id);
  bytes_ += sizeof(Node) + children.capacity() * sizeof(children[0]);
  return id;
}

double Pomcp::rollout(StateId s, int depth) {
  std::uniform_int_distribution<ActionId> act(0, model_.num_actions() - 1);
  double ret = 0.0, g = 1.0;
  for (; depth < max_depth_ && !model_.is_terminal(s); ++depth) {
    const ActionId a = options_.rollout_policy ? options_.rollout_policy(s, rng_) : act(rng_);
    const Step st = model_.step(s, a, rng_);
    ret += g * st.reward;
    g *= gamma_;
    s = st.next;
  }
  return ret;
}

double Pomcp::simulate(StateId s, std::uint32_t node, int depth) {
  if (depth >= max_depth_ || model_.is_terminal(s)) return 0.0;
  if (nodes_[node].actions.empty()) {
    nodes_[node].actions.resize(static_cast<std::size_t>(model_.num_actions()));
    bytes_ += nodes_[node].actions.capacity() * sizeof(ActionStats);
    ++nodes_[node].visits;
    return rollout(s, depth);
  }
  // UCB1; untried actions first.
  const Node& n = nodes_[node];
  const double log_n = std::log(std::max<std::uint32_t>(1, n.visits));
  ActionId best = 0;
  double best_score = -std::numeric_limits<double>::infinity();
  for (std::size_t a = 0; a < n.actions.size(); ++a) {
    const ActionStats& st = n.actions[a];
    const double score = st.visits == 0 ? std::numeric_limits<double>::infinity()
                                        : st.value + c_ * std::sqrt(log_n / st.visits);
    if (score > best_score) {
      best_score = score;
      best = static_cast<ActionId>(a);
    }
  }
  const Step step = model_.step(s, best, rng_);
  double ret = step.reward;
  if (!step.terminal) {
    // Past the node limit the tree stops growing and rollouts take over.
    const std::uint32_t next = child(node, best, step.observation);
    ret += gamma_ *
           (next == kNoNode ? rollout(step.next, depth + 1) : simulate(step.next, next, depth + 1));
  }
  Node& m = nodes_[node];
  ActionStats& st = m.actions[static_cast<std::size_t>(best)];
  ++m.visits;
  ++st.visits;
  st.value += (ret - st.value) / st.visits;
  return ret;
}

ActionId Pomcp::plan(const Budget& budget) {
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  std::uint64_t sims = 0;
  const auto elapsed = [&] { return std::chrono::duration<double>(Clock::now() - t0).count(); };
  if (!belief_.empty() && !is_terminal(model_, belief_)) {
    while (sims < budget.iterations && (sims % 64 != 0 || elapsed() < budget.seconds)) {
      const double ret = simulate(sample_state(belief_, rng_), root_, 0);
      ++sims;
      if (options_.exploration <= 0.0) {
        return_lo_ = have_returns_ ? std::min(return_lo_, ret) : ret;
        return_hi_ = have_returns_ ? std::max(return_hi_, ret) : ret;
        have_returns_ = true;
        if (return_hi_ > return_lo_) c_ = return_hi_ - return_lo_;
      }
    }
  }
  ActionId best = 0;
  double best_value = -std::numeric_limits<double>::infinity();
  for (std::size_t a = 0; a < nodes_[root_].actions.size(); ++a) {
    const ActionStats& st = nodes_[root_].actions[a];
    if (st.visits > 0 && st.value > best_value) {
      best_value = st.value;
      best = static_cast<ActionId>(a);
    }
  }
  stats_.iterations = sims;
  stats_.nodes = nodes_.size();
  stats_.memory_bytes = bytes_;
  stats_.seconds = elapsed();
  stats_.lower = stats_.upper = std::isfinite(best_value) ? best_value : 0.0;
  return best;
}

void Pomcp::advance(ActionId action, ObsId observation, const Belief& next) {
  belief_ = next;
  // Warm: move down and keep the home tree while it has room.
  if (at_home_tree_ && nodes_.size() >= options_.max_nodes / 2) at_home_tree_ = false;
  const Node& r = nodes_[root_];
  if (static_cast<std::size_t>(action) < r.actions.size()) {
    for (const auto& [o, id] : r.actions[static_cast<std::size_t>(action)].children) {
      if (o == observation) {
        if (at_home_tree_) {
          root_ = id;
        } else {
          keep_subtree(id);
        }
        return;
      }
    }
  }
  if (at_home_tree_ && !nodes_[root_].actions.empty() && nodes_.size() < options_.max_nodes) {
    // A branch the search never took: a new leaf of the home tree.
    root_ = child(root_, action, observation);
    return;
  }
  nodes_.assign(1, Node{});
  bytes_ = sizeof(Node);
  root_ = 0;
  at_home_tree_ = false;
}

void Pomcp::keep_subtree(std::uint32_t new_root) {
  std::vector<Node> kept;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> stack{{new_root, 0}};
  kept.emplace_back();
  while (!stack.empty()) {
    const auto [old_id, new_id] = stack.back();
    stack.pop_back();
    Node n = std::move(nodes_[old_id]);
    for (ActionStats& st : n.actions) {
      for (auto& [o, c] : st.children) {
        const auto id = static_cast<std::uint32_t>(kept.size());
        kept.emplace_back();
        stack.emplace_back(c, id);
        c = id;
      }
    }
    kept[new_id] = std::move(n);
  }
  nodes_ = std::move(kept);
  root_ = 0;
  count_bytes();
}

void Pomcp::count_bytes() {
  bytes_ = nodes_.size() * sizeof(Node);
  for (const Node& n : nodes_) {
    bytes_ += n.actions.capacity() * sizeof(ActionStats);
    for (const ActionStats& st : n.actions)
      bytes_ += st.children.capacity() * sizeof(st.children[0]);
  }
}

std::uint32_t Pomcp::root_visits(ActionId a) const {
  const auto& acts = nodes_[root_].actions;
  return static_cast<std::size_t>(a) < acts.size() ? acts[static_cast<std::size_t>(a)].visits : 0;
}

double Pomcp::root_value(ActionId a) const {
  const auto& acts = nodes_[root_].actions;
  return static_cast<std::size_t>(a) < acts.size() ? acts[static_cast<std::size_t>(a)].value : 0.0;
}

}  // namespace plr::pomdp
