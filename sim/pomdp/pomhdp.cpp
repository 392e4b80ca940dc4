#include "plr/pomdp/pomhdp.hpp"

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
  if (options_.warm_start && !nodes_.empty()) {
    std::uint64_t key = 0;
    if (const std::uint32_t id = find(belief, key); id != kUnvisited) {
      root_ = home_ = id;
      nodes_[id].stamp = total_trials_;
      return;
    }
  }
  nodes_.clear();
  index_.clear();
  bytes_ = 0;
  compact_at_ = kSmallGraph;
  epsilon1_ = options_.epsilon1;
  epsilon2_ = options_.epsilon2;
  total_trials_ = 0;
  next_heuristic_ = 0;
  home_ = kUnvisited;
  root_ = node_for(belief);
  if (options_.warm_start) home_ = root_;
}

std::uint32_t Pomhdp::find(const Belief& belief, std::uint64_t& key) const {
  key = belief.signature(options_.belief_resolution);
  for (auto it = index_.find(key); it != index_.end(); it = index_.find(++key)) {
    if (nodes_[it->second].belief.approx_equal(belief, options_.belief_resolution)) {
      return it->second;
    }
  }
  return kUnvisited;
}

std::uint32_t Pomhdp::node_for(Belief belief, const double* bounds) {
  std::uint64_t sig = 0;
  if (const std::uint32_t id = find(belief, sig); id != kUnvisited) return id;
  Node n;
  n.signature = sig;
  n.stamp = total_trials_;
  n.terminal = belief.empty() || is_terminal(model_, belief);
  n.h.assign(inadmissible_.size(), 0.0);
  if (!n.terminal) {
    if (bounds) {
      n.upper = bounds[0];
      n.lower = bounds[1];
      std::copy(bounds + 2, bounds + 2 + n.h.size(), n.h.begin());
    } else {
      n.upper = upper_.value(belief);
      n.lower = std::min(lower_.value(belief), n.upper);
      for (std::size_t i = 0; i < inadmissible_.size(); ++i) {
        n.h[i] = inadmissible_[i]->value(belief);
      }
    }
  }
  n.belief = std::move(belief);
  // Past a small graph, room for the node limit at once: growing by
  // reallocation would stall a search for tens of milliseconds at a time,
  // and reserved pages cost nothing until used.
  if (nodes_.size() == kSmallGraph) {
    const std::size_t room =
        std::min(options_.max_nodes, options_.max_memory_bytes / sizeof(Node) + 1);
    nodes_.reserve(room);
    index_.reserve(room);
  }
  const auto id = static_cast<std::uint32_t>(nodes_.size());
  bytes_ += node_bytes(n);
  nodes_.push_back(std::move(n));
  index_.emplace(sig, id);
  return id;
}

Rng Pomhdp::expansion_rng(std::uint64_t signature, ActionId a) const {
  // A belief expands the same way every time (splitmix64 of its key and the
  // action), so an unvisited child can be made again exactly as it was
  // bounded, also for models that expand by sampling.
  std::uint64_t z = signature ^ (options_.seed * 0x9e3779b97f4a7c15ull) ^
                    (static_cast<std::uint64_t>(a) + 1) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return Rng(z ^ (z >> 31));
}

void Pomhdp::expand(std::uint32_t id) {
  const std::size_t nh = inadmissible_.size();
  std::vector<Edge> edges(static_cast<std::size_t>(model_.num_actions()));
  std::vector<Branch> branches;
  std::vector<double> branch_h;
  // Nothing below adds nodes, so the belief stays where it is.
  const Node& n = nodes_[id];
  model_.prefetch(n.belief);
  std::vector<bool> skip(edges.size());
  for (ActionId a = 0; a < model_.num_actions(); ++a)
    skip[static_cast<std::size_t>(a)] = model_.dominated(n.belief, a);
  if (std::all_of(skip.begin(), skip.end(), [](bool b) { return b; }))
    skip.assign(skip.size(), false);
  for (ActionId a = 0; a < model_.num_actions(); ++a) {
    Edge& edge = edges[static_cast<std::size_t>(a)];
    if (skip[static_cast<std::size_t>(a)]) {
      edge.first = static_cast<std::uint32_t>(branches.size());
      edge.pruned = true;
      continue;
    }
    Rng rng = expansion_rng(n.signature, a);
    const Expansion e = model_.expand(n.belief, a, rng);
    edge.reward = e.reward;
    edge.first = static_cast<std::uint32_t>(branches.size());
    double q_up = 0.0;
    for (const Outcome& o : e.outcomes) {
      Branch b;
      b.probability = o.probability;
      b.observation = o.observation;
      std::uint64_t key = 0;
      if (o.next.empty() || is_terminal(model_, o.next)) {
        b.child = kTerminal;
        branch_h.insert(branch_h.end(), nh, 0.0);
      } else if (const std::uint32_t c = find(o.next, key); c != kUnvisited) {
        b.child = c;
        branch_h.insert(branch_h.end(), nh, 0.0);
      } else {
        b.upper = upper_.value(o.next);
        b.lower = std::min(lower_.value(o.next), b.upper);
        for (std::size_t i = 0; i < nh; ++i) branch_h.push_back(inadmissible_[i]->value(o.next));
      }
      q_up += b.probability * branch_upper(b);
      branches.push_back(b);
    }
    edge.count = static_cast<std::uint32_t>(branches.size()) - edge.first;
    // An action that cannot reach the belief's lower bound is dropped now,
    // before its branches cost memory.
    if (options_.prune_actions && e.reward + gamma_ * q_up < n.lower - 1e-9) {
      branches.resize(edge.first);
      branch_h.resize(static_cast<std::size_t>(edge.first) * nh);
      edge.count = 0;
      edge.pruned = true;
    }
  }
  Node& m = nodes_[id];
  bytes_ -= node_bytes(m);
  m.edges = std::move(edges);
  m.branches = std::move(branches);
  m.branch_h = std::move(branch_h);
  m.branches.shrink_to_fit();
  m.branch_h.shrink_to_fit();
  m.expanded = true;
  bytes_ += node_bytes(m);
}

std::uint32_t Pomhdp::visit(std::uint32_t id, ActionId a, std::size_t k) {
  const std::size_t nh = inadmissible_.size();
  Belief next;
  {
    const Node& n = nodes_[id];
    Rng rng = expansion_rng(n.signature, a);
    Expansion e = model_.expand(n.belief, a, rng);
    for (Outcome& o : e.outcomes) {
      if (o.observation == n.branches[k].observation) {
        next = std::move(o.next);
        break;
      }
    }
  }
  // node_for() may move nodes_: copy the bounds out first.
  std::vector<double> bounds(2 + nh);
  const Branch& b = nodes_[id].branches[k];
  bounds[0] = b.upper;
  bounds[1] = b.lower;
  std::copy_n(nodes_[id].branch_h.begin() + static_cast<std::ptrdiff_t>(k * nh), nh,
              bounds.begin() + 2);
  const std::uint32_t child = node_for(std::move(next), bounds.data());
  nodes_[id].branches[k].child = child;
  return child;
}

double Pomhdp::q_upper(const Node& n, const Edge& e) const {
  if (e.pruned) return -std::numeric_limits<double>::infinity();
  double v = 0.0;
  for (std::uint32_t k = e.first; k < e.first + e.count; ++k) {
    v += n.branches[k].probability * branch_upper(n.branches[k]);
  }
  return e.reward + gamma_ * v;
}

double Pomhdp::q_lower(const Node& n, const Edge& e) const {
  if (e.pruned) return -std::numeric_limits<double>::infinity();
  double v = 0.0;
  for (std::uint32_t k = e.first; k < e.first + e.count; ++k) {
    v += n.branches[k].probability * branch_lower(n.branches[k]);
  }
  return e.reward + gamma_ * v;
}

double Pomhdp::leaf_h(const Node& n, std::size_t i) const {
  if (n.expanded && !n.terminal) return n.h[i];
  // Weighted-A*-style inflation of the cost-to-go v_max - h; a terminal
  // belief's value is 0, so its cost-to-go is v_max (0 for goal-directed
  // models: goals stay free, as in MHA*).
  return inflate(n.terminal ? 0.0 : n.h[i]);
}

double Pomhdp::q_h(const Node& n, const Edge& e, std::size_t i) const {
  if (e.pruned) return -std::numeric_limits<double>::infinity();
  const std::size_t nh = inadmissible_.size();
  double v = 0.0;
  for (std::uint32_t k = e.first; k < e.first + e.count; ++k) {
    const Branch& b = n.branches[k];
    const double h = b.child == kTerminal    ? inflate(0.0)
                     : b.child == kUnvisited ? inflate(n.branch_h[k * nh + i])
                                             : leaf_h(nodes_[b.child], i);
    v += b.probability * h;
  }
  return e.reward + gamma_ * v;
}

void Pomhdp::backup(std::uint32_t id) {
  Node& n = nodes_[id];
  if (n.terminal || !n.expanded) return;
  double best_u = -std::numeric_limits<double>::infinity(), best_l = best_u;
  for (const Edge& e : n.edges) {
    best_u = std::max(best_u, q_upper(n, e));
    best_l = std::max(best_l, q_lower(n, e));
  }
  // Both are valid bounds before and after: keep the tighter one.
  n.upper = std::min(n.upper, best_u);
  n.lower = std::min(std::max(n.lower, best_l), n.upper);
  if (options_.prune_actions) {
    for (Edge& e : n.edges) {
      if (!e.pruned && q_upper(n, e) < n.lower - 1e-9) e.pruned = true;
    }
  }
  for (std::size_t i = 0; i < n.h.size(); ++i) {
    double best = -std::numeric_limits<double>::infinity();
    for (const Edge& e : n.edges) best = std::max(best, q_h(n, e, i));
    n.h[i] = best;
  }
}

ActionId Pomhdp::choose_action(const Node& n, std::size_t heuristic) const {
  ActionId anchor = 0;
  double anchor_q = -std::numeric_limits<double>::infinity();
  for (std::size_t a = 0; a < n.edges.size(); ++a) {
    const double q = q_upper(n, n.edges[a]);
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
    const double q = q_h(n, n.edges[a], i);
    if (q > pick_q) {
      pick_q = q;
      pick = static_cast<ActionId>(a);
    }
  }
  // MHA*'s rule: an inadmissible search goes on only while its choice costs,
  // by the anchor's admissible estimate, at most epsilon2 times the anchor's
  // best; otherwise the anchor's choice is taken.
  const double anchor_cost = v_max_ - anchor_q;
  const double pick_cost = v_max_ - q_upper(n, n.edges[static_cast<std::size_t>(pick)]);
  return pick_cost <= epsilon2_ * anchor_cost + 1e-12 ? pick : anchor;
}

void Pomhdp::trial(std::size_t heuristic, Clock::time_point deadline) {
  path_.clear();
  std::uint32_t id = root_;
  double threshold = std::max(options_.target_gap, options_.trial_gap_fraction *
                                                       (nodes_[root_].upper - nodes_[root_].lower));
  for (int depth = 0;; ++depth) {
    nodes_[id].stamp = total_trials_;
    if (nodes_[id].terminal) break;
    // HSVI's stopping rule: a gap this small here cannot matter at the root.
    if (depth > 0 && nodes_[id].upper - nodes_[id].lower <= threshold) break;
    if (!nodes_[id].expanded) {
      expand(id);
      backup(id);
    }
    if (depth >= max_depth_ || !room_left()) break;
    // Out of time: stop descending, still back up what was found.
    if ((depth & 7) == 7 && Clock::now() >= deadline) break;
    const Node& n = nodes_[id];
    const ActionId a = choose_action(n, heuristic);
    const Edge& e = n.edges[static_cast<std::size_t>(a)];
    // The outcome whose gap weighs most.
    double best = 0.0;
    std::size_t pick = n.branches.size();
    for (std::uint32_t k = e.first; k < e.first + e.count; ++k) {
      const Branch& b = n.branches[k];
      const double w = b.probability * (branch_upper(b) - branch_lower(b));
      if (w > best) {
        best = w;
        pick = k;
      }
    }
    if (pick == n.branches.size()) break;
    const double next_threshold = gamma_ > 0.0 && gamma_ < 1.0 ? threshold / gamma_ : threshold;
    const Branch& b = n.branches[pick];
    // The same rule before a child is made a node: one too close to call is
    // left unvisited.
    if (branch_upper(b) - branch_lower(b) <= next_threshold) break;
    const std::uint32_t next = b.child == kUnvisited ? visit(id, a, pick) : b.child;
    path_.push_back(id);
    id = next;
    threshold = next_threshold;
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
    const double l = q_lower(n, n.edges[a]);
    if (l > best_lower) {
      best_lower = l;
      best = a;
    }
  }
  for (std::size_t a = 0; a < n.edges.size(); ++a) {
    if (a != best && q_upper(n, n.edges[a]) > best_lower + options_.settle_tolerance) return false;
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
         !(until_settled && settled()) && Clock::now() < deadline) {
    if (!room_left()) {
      if (!options_.reclaim) break;
      reclaim();
      if (!room_left()) break;
    }
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
  double best_l = -std::numeric_limits<double>::infinity();
  double best_u = best_l;
  for (std::size_t a = 0; a < n.edges.size(); ++a) {
    const double l = q_lower(n, n.edges[a]), u = q_upper(n, n.edges[a]);
    if (l > best_l + 1e-12 || (l > best_l - 1e-12 && u > best_u)) {
      best = static_cast<ActionId>(a);
      best_l = l;
      best_u = u;
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
  // What the new root cannot reach is dropped once the graph has doubled
  // (and by reclaim() at a limit).
  if (nodes_.size() >= compact_at_) compact();
}

void Pomhdp::compact() {
  // Mark what the root and the home node reach, then move the kept nodes
  // down in place (a kept node's new index is never above its old one).
  constexpr std::uint32_t kMarked = 0;
  std::vector<std::uint32_t> remap(nodes_.size(), kUnvisited);
  std::vector<std::uint32_t> stack;
  const auto mark = [&](std::uint32_t id) {
    if (id < kTerminal && remap[id] == kUnvisited) {
      remap[id] = kMarked;
      stack.push_back(id);
    }
  };
  mark(root_);
  mark(home_);
  while (!stack.empty()) {
    const std::uint32_t id = stack.back();
    stack.pop_back();
    for (const Branch& b : nodes_[id].branches) mark(b.child);
  }
  std::uint32_t kept = 0;
  for (std::uint32_t& r : remap) {
    if (r != kUnvisited) r = kept++;
  }
  for (std::uint32_t i = 0; i < nodes_.size(); ++i) {
    if (remap[i] != kUnvisited && remap[i] != i) nodes_[remap[i]] = std::move(nodes_[i]);
  }
  nodes_.resize(kept);
  bytes_ = 0;
  index_.clear();
  for (std::uint32_t i = 0; i < nodes_.size(); ++i) {
    for (Branch& b : nodes_[i].branches) {
      if (b.child < kTerminal) b.child = remap[b.child];
    }
    bytes_ += node_bytes(nodes_[i]);
    index_.emplace(nodes_[i].signature, i);
  }
  root_ = remap[root_];
  if (home_ < kTerminal) home_ = remap[home_];
  compact_at_ = std::max(kSmallGraph, 2 * nodes_.size());
}

void Pomhdp::reclaim() {
  ++reclaims_;
  std::vector<std::uint64_t> stamps;
  stamps.reserve(nodes_.size());
  for (const Node& n : nodes_) stamps.push_back(n.stamp);
  const auto mid = stamps.begin() + static_cast<std::ptrdiff_t>(stamps.size() / 2);
  std::nth_element(stamps.begin(), mid, stamps.end());
  const std::uint64_t cutoff = *mid;
  std::vector<char> drop(nodes_.size(), 0);
  for (std::size_t i = 0; i < nodes_.size(); ++i) drop[i] = nodes_[i].stamp <= cutoff ? 1 : 0;
  drop[root_] = 0;
  if (home_ < kTerminal) drop[home_] = 0;
  // A dropped child leaves its bounds (and its heuristic estimates, the
  // backed-up ones deflated back to raw values) in the branches leading to
  // it, which become unvisited again.
  const std::size_t nh = inadmissible_.size();
  for (std::size_t i = 0; i < nodes_.size(); ++i) {
    if (drop[i]) continue;
    Node& n = nodes_[i];
    for (std::size_t k = 0; k < n.branches.size(); ++k) {
      Branch& b = n.branches[k];
      if (b.child >= kTerminal || !drop[b.child]) continue;
      const Node& c = nodes_[b.child];
      if (c.terminal) {
        b.child = kTerminal;
        continue;
      }
      b.upper = c.upper;
      b.lower = c.lower;
      for (std::size_t j = 0; j < nh; ++j) {
        n.branch_h[k * nh + j] = c.expanded ? v_max_ - (v_max_ - c.h[j]) / epsilon1_ : c.h[j];
      }
      b.child = kUnvisited;
    }
  }
  compact();
}

PolicyTree Pomhdp::policy_tree(int horizon, bool expand_unvisited) {
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
    const Edge e = nodes_[item.graph].edges[static_cast<std::size_t>(a)];
    std::vector<std::pair<ObsId, std::uint32_t>> children;
    for (std::uint32_t b = e.first; b < e.first + e.count; ++b) {
      std::uint32_t child = nodes_[item.graph].branches[b].child;
      if (child == kTerminal) continue;
      if (child == kUnvisited) {
        if (!expand_unvisited) continue;
        child = visit(item.graph, a, b);
      }
      if (nodes_[child].terminal || (!expand_unvisited && !nodes_[child].expanded)) continue;
      children.emplace_back(nodes_[item.graph].branches[b].observation,
                            static_cast<std::uint32_t>(queue.size()));
      queue.push_back({child, item.depth + 1});
      tree.nodes.emplace_back();
    }
    std::sort(children.begin(), children.end());
    tree.nodes[k].children = std::move(children);
  }
  root_ = saved_root;
  return tree;
}

std::size_t Pomhdp::node_bytes(const Node& n) const {
  // The node, its particles, heuristic values, edges and branches, and its
  // index entry.
  return sizeof(Node) + 32 + n.belief.particles().capacity() * sizeof(Particle) +
         n.h.capacity() * sizeof(double) + n.edges.capacity() * sizeof(Edge) +
         n.branches.capacity() * sizeof(Branch) + n.branch_h.capacity() * sizeof(double);
}

}  // namespace plr::pomdp
