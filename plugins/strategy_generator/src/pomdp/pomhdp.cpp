#include "pomdp/pomhdp.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace plr::pomdp {
namespace {

using Clock = std::chrono::steady_clock;

constexpr std::size_t kSmallGraph = 1 << 16;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

}  // namespace

Pomhdp::Pomhdp(const GenerativeModel& model, const Heuristic& upper, const Heuristic& lower,
               std::vector<const Heuristic*> inadmissible, PomhdpOptions options)
    : model_(model),
      upper_(upper),
      lower_(lower),
      inadmissible_(std::move(inadmissible)),
      options_(options),
      rng_(options.seed),
      gamma_(model.discount()),
      epsilon1_(options.epsilon1),
      epsilon2_(options.epsilon2) {
  // Costs are measured down from the best value any belief can have, so the
  // MHA*-style factors scale non-negative numbers (for goal-directed models
  // rewards are costs already and the best value is 0).
  v_max_ = gamma_ < 1.0 ? std::max(0.0, model.max_reward()) / (1.0 - gamma_) : 0.0;
  if (options.max_depth > 0) {
    max_depth_ = options.max_depth;
  } else if (gamma_ < 1.0) {
    const double range =
        std::max(1e-12, (model.max_reward() - model.min_reward()) / (1.0 - gamma_));
    const double d = std::log(std::max(1e-12, options.target_gap) / range) / std::log(gamma_);
    max_depth_ = static_cast<int>(std::clamp(std::ceil(d), 1.0, 1000.0));
  } else {
    max_depth_ = 100;
  }
  reset(model.initial_belief());
}

void Pomhdp::reset(const Belief& belief) {
  nodes_.clear();
  index_.clear();
  bytes_ = 0;
  compact_at_ = kSmallGraph;
  epsilon1_ = options_.epsilon1;
  epsilon2_ = options_.epsilon2;
  total_trials_ = 0;
  next_heuristic_ = 0;
  root_ = node_for(belief);
}

std::uint32_t Pomhdp::node_for(Belief belief) {
  std::uint64_t sig = belief.signature(options_.belief_resolution);
  for (auto it = index_.find(sig); it != index_.end(); it = index_.find(++sig)) {
    if (nodes_[it->second].belief.approx_equal(belief, options_.belief_resolution))
      return it->second;
  }
  Node n;
  n.signature = sig;
  n.terminal = belief.empty() || is_terminal(model_, belief);
  n.h.assign(inadmissible_.size(), 0.0);
  if (!n.terminal) {
    n.upper = upper_.value(belief);
    n.lower = std::min(lower_.value(belief), n.upper);
    for (std::size_t i = 0; i < inadmissible_.size(); ++i) n.h[i] = inadmissible_[i]->value(belief);
  }
  n.belief = std::move(belief);
  // Past a small graph, room for the node limit at once: growing by
  // reallocation would stall a search for tens of milliseconds at a time,
  // and reserved pages cost nothing until used.
  if (nodes_.size() == kSmallGraph) {
    nodes_.reserve(options_.max_nodes);
    index_.reserve(options_.max_nodes);
  }
  const auto id = static_cast<std::uint32_t>(nodes_.size());
  bytes_ += node_bytes(n);
  nodes_.push_back(std::move(n));
  index_.emplace(sig, id);
  return id;
}

void Pomhdp::expand(std::uint32_t id) {
  std::vector<Edge> edges(static_cast<std::size_t>(model_.num_actions()));
  for (ActionId a = 0; a < model_.num_actions(); ++a) {
    // nodes_ may grow below: look the belief up again for every action.
    Expansion e = model_.expand(nodes_[id].belief, a, rng_);
    Edge& edge = edges[static_cast<std::size_t>(a)];
    edge.reward = e.reward;
    edge.branches.reserve(e.outcomes.size());
    for (Outcome& o : e.outcomes) {
      edge.branches.push_back({o.observation, o.probability, node_for(std::move(o.next))});
    }
  }
  bytes_ -= node_bytes(nodes_[id]);
  nodes_[id].edges = std::move(edges);
  nodes_[id].expanded = true;
  bytes_ += node_bytes(nodes_[id]);
}

double Pomhdp::q_upper(const Edge& e) const {
  double v = 0.0;
  for (const Branch& b : e.branches) v += b.probability * nodes_[b.child].upper;
  return e.reward + gamma_ * v;
}

double Pomhdp::q_lower(const Edge& e) const {
  double v = 0.0;
  for (const Branch& b : e.branches) v += b.probability * nodes_[b.child].lower;
  return e.reward + gamma_ * v;
}

double Pomhdp::leaf_h(const Node& n, std::size_t i) const {
  if (n.expanded && !n.terminal) return n.h[i];
  // Weighted-A*-style inflation of the cost-to-go v_max - h; a terminal
  // belief's value is 0, so its cost-to-go is v_max (0 for goal-directed
  // models: goals stay free, as in MHA*).
  return v_max_ - epsilon1_ * (v_max_ - (n.terminal ? 0.0 : n.h[i]));
}

double Pomhdp::q_h(const Edge& e, std::size_t i) const {
  double v = 0.0;
  for (const Branch& b : e.branches) v += b.probability * leaf_h(nodes_[b.child], i);
  return e.reward + gamma_ * v;
}

void Pomhdp::backup(std::uint32_t id) {
  Node& n = nodes_[id];
  if (n.terminal || !n.expanded) return;
  double best_u = -std::numeric_limits<double>::infinity(), best_l = best_u;
  for (const Edge& e : n.edges) {
    best_u = std::max(best_u, q_upper(e));
    best_l = std::max(best_l, q_lower(e));
  }
  // Both are valid bounds before and after: keep the tighter one.
  n.upper = std::min(n.upper, best_u);
  n.lower = std::min(std::max(n.lower, best_l), n.upper);
  for (std::size_t i = 0; i < n.h.size(); ++i) {
    double best = -std::numeric_limits<double>::infinity();
    for (const Edge& e : n.edges) best = std::max(best, q_h(e, i));
    n.h[i] = best;
  }
}

ActionId Pomhdp::choose_action(const Node& n, std::size_t heuristic) const {
  ActionId anchor = 0;
  double anchor_q = -std::numeric_limits<double>::infinity();
  for (std::size_t a = 0; a < n.edges.size(); ++a) {
    const double q = q_upper(n.edges[a]);
    if (q > anchor_q) {
      anchor_q = q;
      anchor = static_cast<ActionId>(a);
    }
  }
  if (heuristic == 0) return anchor;
  const std::size_t i = heuristic - 1;
  ActionId pick = 0;
  double pick_q = -std::numeric_limits<double>::infinity();
  for (std::size_t a = 0; a < n.edges.size(); ++a) {
    const double q = q_h(n.edges[a], i);
    if (q > pick_q) {
      pick_q = q;
      pick = static_cast<ActionId>(a);
    }
  }
  // MHA*'s rule: an inadmissible search goes on only while its choice costs,
  // by the anchor's admissible estimate, at most epsilon2 times the anchor's
  // best; otherwise the anchor's choice is taken.
  const double anchor_cost = v_max_ - anchor_q;
  const double pick_cost = v_max_ - q_upper(n.edges[static_cast<std::size_t>(pick)]);
  return pick_cost <= epsilon2_ * anchor_cost + 1e-12 ? pick : anchor;
}

void Pomhdp::trial(std::size_t heuristic, Clock::time_point deadline) {
  path_.clear();
  std::uint32_t id = root_;
  double threshold = options_.target_gap;
  for (int depth = 0;; ++depth) {
    if (nodes_[id].terminal) break;
    // HSVI's stopping rule: a gap this small here cannot matter at the root.
    if (depth > 0 && nodes_[id].upper - nodes_[id].lower <= threshold) break;
    if (!nodes_[id].expanded) {
      expand(id);
      backup(id);
    }
    if (depth >= max_depth_ || nodes_.size() >= options_.max_nodes) break;
    // Out of time: stop descending, still back up what was found.
    if ((depth & 7) == 7 && Clock::now() >= deadline) break;
    const Edge& e =
        nodes_[id].edges[static_cast<std::size_t>(choose_action(nodes_[id], heuristic))];
    // The outcome whose gap weighs most.
    double best = 0.0;
    std::uint32_t next = id;
    for (const Branch& b : e.branches) {
      const Node& c = nodes_[b.child];
      const double w = b.probability * (c.upper - c.lower);
      if (w > best) {
        best = w;
        next = b.child;
      }
    }
    if (next == id && best == 0.0) break;
    path_.push_back(id);
    id = next;
    if (gamma_ > 0.0 && gamma_ < 1.0) threshold /= gamma_;
  }
  backup(id);
  for (auto it = path_.rbegin(); it != path_.rend(); ++it) backup(*it);
}

bool Pomhdp::settled() const {
  const Node& n = nodes_[root_];
  if (!n.expanded) return false;
  double best_lower = -std::numeric_limits<double>::infinity();
  std::size_t best = 0;
  for (std::size_t a = 0; a < n.edges.size(); ++a) {
    const double l = q_lower(n.edges[a]);
    if (l > best_lower) {
      best_lower = l;
      best = a;
    }
  }
  for (std::size_t a = 0; a < n.edges.size(); ++a) {
    if (a != best && q_upper(n.edges[a]) > best_lower + options_.settle_tolerance) return false;
  }
  return true;
}

PlanStats Pomhdp::solve(const Budget& budget) {
  return run(budget, false);
}

PlanStats Pomhdp::run(const Budget& budget, bool until_settled) {
  const auto t0 = Clock::now();
  const auto deadline = std::isfinite(budget.seconds)
                            ? t0 + std::chrono::duration_cast<Clock::duration>(
                                       std::chrono::duration<double>(budget.seconds))
                            : Clock::time_point::max();
  std::uint64_t trials = 0;
  while (trials < budget.iterations && !nodes_[root_].terminal &&
         nodes_[root_].upper - nodes_[root_].lower > options_.target_gap &&
         !(until_settled && settled()) && nodes_.size() < options_.max_nodes &&
         Clock::now() < deadline) {
    // Round robin over the inadmissible heuristics (each falls back to the
    // anchor where it strays too far); the anchor alone when there are none.
    const std::size_t h = inadmissible_.empty() ? 0 : 1 + next_heuristic_++ % inadmissible_.size();
    trial(h, deadline);
    ++trials;
    ++total_trials_;
    if (options_.epsilon_period > 0 &&
        total_trials_ % static_cast<std::uint64_t>(options_.epsilon_period) == 0) {
      epsilon1_ = 1.0 + (epsilon1_ - 1.0) / 2.0;
      epsilon2_ = 1.0 + (epsilon2_ - 1.0) / 2.0;
    }
  }
  stats_.iterations = trials;
  stats_.nodes = nodes_.size();
  stats_.memory_bytes = bytes_;
  stats_.seconds = seconds_since(t0);
  stats_.lower = nodes_[root_].lower;
  stats_.upper = nodes_[root_].upper;
  return stats_;
}

ActionId Pomhdp::best_action() {
  if (nodes_[root_].terminal) return 0;
  if (!nodes_[root_].expanded) {
    expand(root_);
    backup(root_);
  }
  const Node& n = nodes_[root_];
  ActionId best = 0;
  for (std::size_t a = 1; a < n.edges.size(); ++a) {
    const double l = q_lower(n.edges[a]), lb = q_lower(n.edges[static_cast<std::size_t>(best)]);
    if (l > lb + 1e-12 ||
        (l > lb - 1e-12 &&
         q_upper(n.edges[a]) > q_upper(n.edges[static_cast<std::size_t>(best)]))) {
      best = static_cast<ActionId>(a);
    }
  }
  return best;
}

ActionId Pomhdp::plan(const Budget& budget) {
  run(budget, options_.settle_tolerance >= 0.0);
  const ActionId a = best_action();
  stats_.nodes = nodes_.size();
  stats_.memory_bytes = bytes_;
  stats_.lower = nodes_[root_].lower;
  stats_.upper = nodes_[root_].upper;
  return a;
}

void Pomhdp::advance(ActionId /*action*/, ObsId /*observation*/, const Belief& next) {
  // The child of (action, observation) has this belief when the model is
  // exact; node_for() finds it by its signature, or starts a new root.
  root_ = node_for(next);
  // Also at half the node limit, or a search that reached the limit could
  // never free room again.
  if (nodes_.size() >= std::min(compact_at_, options_.max_nodes / 2)) compact(root_);
}

void Pomhdp::compact(std::uint32_t new_root) {
  std::vector<std::uint32_t> remap(nodes_.size(), std::numeric_limits<std::uint32_t>::max());
  std::vector<std::uint32_t> order{new_root};
  remap[new_root] = 0;
  for (std::size_t k = 0; k < order.size(); ++k) {
    for (const Edge& e : nodes_[order[k]].edges) {
      for (const Branch& b : e.branches) {
        if (remap[b.child] == std::numeric_limits<std::uint32_t>::max()) {
          remap[b.child] = static_cast<std::uint32_t>(order.size());
          order.push_back(b.child);
        }
      }
    }
  }
  std::vector<Node> kept;
  kept.reserve(std::max(order.size(), nodes_.capacity()));
  for (std::uint32_t old : order) {
    kept.push_back(std::move(nodes_[old]));
    for (Edge& e : kept.back().edges) {
      for (Branch& b : e.branches) b.child = remap[b.child];
    }
  }
  nodes_ = std::move(kept);
  bytes_ = 0;
  for (const Node& n : nodes_) bytes_ += node_bytes(n);
  index_.clear();
  for (std::uint32_t i = 0; i < nodes_.size(); ++i) index_.emplace(nodes_[i].signature, i);
  root_ = 0;
  compact_at_ = std::max(kSmallGraph, 2 * nodes_.size());
}

PolicyTree Pomhdp::policy_tree(int horizon) {
  PolicyTree tree;
  if (horizon <= 0) return tree;
  struct Item {
    std::uint32_t graph;
    int depth;
  };
  const std::uint32_t saved_root = root_;
  std::vector<Item> queue{{root_, 1}};
  tree.nodes.emplace_back();
  for (std::size_t k = 0; k < queue.size(); ++k) {
    const Item item = queue[k];
    root_ = item.graph;  // best_action() works on the root
    const ActionId a = best_action();
    PolicyNode& pn = tree.nodes[k];
    pn.action = a;
    pn.lower = nodes_[item.graph].lower;
    pn.upper = nodes_[item.graph].upper;
    if (item.depth >= horizon || nodes_[item.graph].terminal) continue;
    const Edge& e = nodes_[item.graph].edges[static_cast<std::size_t>(a)];
    std::vector<std::pair<ObsId, std::uint32_t>> children;
    for (const Branch& b : e.branches) {
      if (nodes_[b.child].terminal) continue;
      children.emplace_back(b.observation, static_cast<std::uint32_t>(queue.size()));
      queue.push_back({b.child, item.depth + 1});
      tree.nodes.emplace_back();
    }
    std::sort(children.begin(), children.end());
    tree.nodes[k].children = std::move(children);
  }
  root_ = saved_root;
  return tree;
}

std::size_t Pomhdp::node_bytes(const Node& n) const {
  // The node, its particles, heuristic values and edges, and its index entry.
  std::size_t bytes = sizeof(Node) + 32 + n.belief.particles().capacity() * sizeof(Particle) +
                      n.h.capacity() * sizeof(double) + n.edges.capacity() * sizeof(Edge);
  for (const Edge& e : n.edges) bytes += e.branches.capacity() * sizeof(Branch);
  return bytes;
}

}  // namespace plr::pomdp
