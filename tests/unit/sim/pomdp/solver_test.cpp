#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "plr/pomdp/evaluate.hpp"
#include "plr/pomdp/heuristics.hpp"
#include "plr/pomdp/model_io.hpp"
#include "plr/pomdp/pomcp.hpp"
#include "plr/pomdp/pomhdp.hpp"
#include "test_models.hpp"

namespace plr::pomdp {
namespace {

using test::kBandit;
using test::kSense;
using test::parse_or_die;

const Budget kTrials1{std::numeric_limits<double>::infinity(), 1};

Budget trials(std::uint64_t n) {
  return {std::numeric_limits<double>::infinity(), n};
}

// Bandit at the uniform belief, g = 0.5: the blind bound is exact (always go:
// 1 / (1 - g) = 2) and FIB gives max over actions of
// alpha_go = (0 + g * 2, 2 + g * 4) -> 2.5.
TEST(Bounds, BanditByHand) {
  const TabularModel m = parse_or_die(kBandit, "bandit");
  const TabularHeuristics h = make_tabular_heuristics(m);
  const Belief b = m.initial_belief();
  EXPECT_NEAR(h.lower->value(b), 2.0, 1e-6);
  EXPECT_NEAR(h.upper->value(b), 2.5, 1e-6);
  // V_MDP(s0) = 1 / (1 - g) = 2, V_MDP(s1) = 2 / (1 - g) = 4.
  EXPECT_NEAR(h.most_likely->value(Belief({{0, 0.6}, {1, 0.4}})), 2.0, 1e-6);
  EXPECT_NEAR(h.most_likely->value(Belief({{0, 0.4}, {1, 0.6}})), 4.0, 1e-6);
}

// One trial of depth 1 on the bandit: the root is its own child (the belief
// never changes), so the trial backs it up twice:
// U = min(2.5, 1 + g * 2.5) = 2.25, then 1 + g * 2.25 = 2.125, then
// 1 + g * 2.125 = 2.0625; L stays at the exact 2.
TEST(Pomhdp, BackupsByHand) {
  const TabularModel m = parse_or_die(kBandit, "bandit");
  const TabularHeuristics h = make_tabular_heuristics(m);
  PomhdpOptions o;
  o.max_depth = 1;
  Pomhdp solver(m, *h.upper, *h.lower, {}, o);
  const PlanStats s = solver.solve(kTrials1);
  EXPECT_EQ(s.iterations, 1u);
  EXPECT_EQ(solver.num_nodes(), 1u);
  EXPECT_NEAR(solver.upper(), 2.0625, 1e-6);
  EXPECT_NEAR(solver.lower(), 2.0, 1e-6);
  EXPECT_EQ(solver.best_action(), 1);
}

// Sense: FIB is exact at the uniform belief (1), the blind bound is 0; one
// expansion shows the sensed beliefs are worth 2 each, so L = 0 + g * 2 = 1.
TEST(Pomhdp, TwoStepValueByHand) {
  const TabularModel m = parse_or_die(kSense, "sense");
  const TabularHeuristics h = make_tabular_heuristics(m);
  EXPECT_NEAR(h.upper->value(m.initial_belief()), 1.0, 1e-6);
  EXPECT_NEAR(h.lower->value(m.initial_belief()), 0.0, 1e-6);
  Pomhdp solver(m, *h.upper, *h.lower, h.inadmissible());
  solver.solve(trials(100));
  EXPECT_NEAR(solver.lower(), 1.0, 1e-6);
  EXPECT_NEAR(solver.upper(), 1.0, 1e-6);
  EXPECT_EQ(solver.best_action(), 0);
  // The policy tree: sense, then pick the side seen.
  const PolicyTree tree = solver.policy_tree(2);
  ASSERT_EQ(tree.nodes.size(), 3u);
  EXPECT_EQ(tree.nodes[tree.root].action, 0);
  EXPECT_EQ(tree.nodes[*tree.next(tree.root, 0)].action, 1);
  EXPECT_EQ(tree.nodes[*tree.next(tree.root, 1)].action, 2);
  // Two steps of it earn 0 then g * 1, every time.
  EvaluationOptions eo;
  eo.episodes = 50;
  const Evaluation e = evaluate_tree(m, tree, eo);
  EXPECT_DOUBLE_EQ(e.mean, 0.5);
  EXPECT_DOUBLE_EQ(e.ci95, 0.0);
}

// Discount 0: the value is the best immediate expected reward; Tiger's
// listen (-1) beats opening a door (-45).
TEST(Pomhdp, OneStepValueByHand) {
  TabularModel m = parse_or_die(R"(discount: 0
states: left right
actions: listen open-left open-right
observations: hear-left hear-right
T: listen identity
T: open-left uniform
T: open-right uniform
O: listen
0.85 0.15
0.15 0.85
O: open-left uniform
O: open-right uniform
R: listen : * : * : * -1
R: open-left : left : * : * -100
R: open-left : right : * : * 10
R: open-right : left : * : * 10
R: open-right : right : * : * -100
)",
                                "tiger0");
  const TabularHeuristics h = make_tabular_heuristics(m);
  Pomhdp solver(m, *h.upper, *h.lower, h.inadmissible());
  solver.solve(trials(10));
  EXPECT_NEAR(solver.lower(), -1.0, 1e-9);
  EXPECT_NEAR(solver.upper(), -1.0, 1e-9);
  EXPECT_EQ(solver.best_action(), 0);
}

// The MHA*-style factors move halfway to 1 every epsilon_period trials.
TEST(Pomhdp, EpsilonSchedule) {
  auto m = load_model(std::filesystem::path(PLR_POMDP_BENCHMARKS) / "Tiger.pomdp");
  ASSERT_TRUE(m);
  const TabularHeuristics h = make_tabular_heuristics(*m);
  PomhdpOptions o;
  o.epsilon1 = 9.0;
  o.epsilon2 = 5.0;
  o.epsilon_period = 4;
  o.target_gap = 0.0;
  Pomhdp solver(*m, *h.upper, *h.lower, h.inadmissible(), o);
  solver.solve(trials(8));
  EXPECT_EQ(solver.total_trials(), 8u);
  EXPECT_DOUBLE_EQ(solver.epsilon1(), 3.0);
  EXPECT_DOUBLE_EQ(solver.epsilon2(), 2.0);
}

// Tiger (g = 0.95): the bounds close on 19.37 and keep their order all the
// way; the online policy's simulated value has 19.37 in its interval.
TEST(Pomhdp, TigerBoundsAndValue) {
  const auto file = std::filesystem::path(PLR_POMDP_BENCHMARKS) / "Tiger.pomdp";
  auto m = load_model(file);
  ASSERT_TRUE(m) << m.error().message;
  const TabularHeuristics h = make_tabular_heuristics(*m);
  EXPECT_NEAR(h.lower->value(m->initial_belief()), -20.0, 1e-4);  // always listen
  PomhdpOptions o;
  o.target_gap = 0.01;
  Pomhdp solver(*m, *h.upper, *h.lower, h.inadmissible(), o);
  double lower = solver.lower(), upper = solver.upper();
  for (int i = 0; i < 200 && solver.upper() - solver.lower() > 0.01; ++i) {
    solver.solve(trials(20));
    EXPECT_LE(solver.lower(), solver.upper());
    EXPECT_GE(solver.lower(), lower);
    EXPECT_LE(solver.upper(), upper);
    lower = solver.lower();
    upper = solver.upper();
  }
  EXPECT_LE(solver.total_trials(), 4000u);
  EXPECT_NEAR(solver.lower(), 19.371, 0.02);
  EXPECT_NEAR(solver.upper(), 19.371, 0.02);
  EXPECT_EQ(solver.best_action(), 0);  // listen first

  EvaluationOptions eo;
  eo.episodes = 400;
  eo.per_step = trials(4000);
  eo.seed = 7;
  const Evaluation e = evaluate(*m, solver, eo);
  EXPECT_LE(e.mean - e.ci95, 19.371);
  EXPECT_GE(e.mean + e.ci95, 19.371);
}

// Only the beliefs a trial enters become nodes: one trial of depth 1 on Tiger
// expands the root (listen branches to two beliefs, either door back to the
// uniform root) and enters one child, so the graph has two nodes; the other
// listen outcome is a branch with bounds and no belief.
TEST(Pomhdp, UnvisitedChildrenAreNotNodes) {
  const auto file = std::filesystem::path(PLR_POMDP_BENCHMARKS) / "Tiger.pomdp";
  auto m = load_model(file);
  ASSERT_TRUE(m) << m.error().message;
  const TabularHeuristics h = make_tabular_heuristics(*m);
  PomhdpOptions o;
  o.max_depth = 1;
  Pomhdp solver(*m, *h.upper, *h.lower, {}, o);
  solver.solve(kTrials1);
  EXPECT_EQ(solver.num_nodes(), 2u);
  // The policy tree makes the other child when it needs it.
  const PolicyTree tree = solver.policy_tree(2);
  EXPECT_EQ(tree.nodes.size(), 3u);
  EXPECT_EQ(solver.num_nodes(), 3u);
}

// A child made when a trial first enters it (from the parent, by the same
// expansion) holds the belief an exact Bayes update gives: along the policy
// tree of RockSample(4,4), advancing to each exact belief finds the node the
// tree made, so the graph does not grow.
TEST(Pomhdp, LazyChildIsTheExactUpdate) {
  const auto file = std::filesystem::path(PLR_POMDP_BENCHMARKS) / "RockSample_4_4.pomdp";
  auto m = load_model(file);
  ASSERT_TRUE(m) << m.error().message;
  const TabularHeuristics h = make_tabular_heuristics(*m);
  Pomhdp solver(*m, *h.upper, *h.lower, h.inadmissible());
  solver.solve(trials(2000));
  const PolicyTree tree = solver.policy_tree(12);
  const std::size_t nodes = solver.num_nodes();
  ASSERT_GT(tree.nodes.size(), 6u);
  Rng rng(1);
  std::vector<std::pair<std::uint32_t, Belief>> stack{{tree.root, m->initial_belief()}};
  int checked = 0;
  while (!stack.empty()) {
    auto [k, belief] = std::move(stack.back());
    stack.pop_back();
    for (const auto& [o, child] : tree.nodes[k].children) {
      Belief next = update_belief(*m, belief, tree.nodes[k].action, o, rng);
      solver.advance(tree.nodes[k].action, o, next);
      EXPECT_EQ(solver.num_nodes(), nodes);
      ++checked;
      stack.emplace_back(child, std::move(next));
    }
  }
  EXPECT_EQ(checked + 1, static_cast<int>(tree.nodes.size()));
}

// Online, a step's search stops once the root's bounds are within the
// target gap, long before its trial budget; a smaller target takes more.
TEST(Pomhdp, PlanStopsAtTheTargetGap) {
  const auto file = std::filesystem::path(PLR_POMDP_BENCHMARKS) / "Tiger.pomdp";
  auto m = load_model(file);
  ASSERT_TRUE(m) << m.error().message;
  const TabularHeuristics h = make_tabular_heuristics(*m);
  std::uint64_t previous = 0;
  for (const double gap : {1.0, 1e-3}) {
    PomhdpOptions o;
    o.target_gap = gap;
    o.settle_tolerance = -1.0;  // the gap alone stops it
    Pomhdp solver(*m, *h.upper, *h.lower, h.inadmissible(), o);
    EXPECT_EQ(solver.plan(trials(1'000'000)), 0);  // listen
    const PlanStats& s = solver.last_stats();
    EXPECT_LT(s.iterations, 1'000'000u);
    EXPECT_LE(s.upper - s.lower, gap);
    EXPECT_GT(s.upper - s.lower, 0.0);
    EXPECT_GT(s.iterations, previous);
    previous = s.iterations;
  }
}

// At the node limit the older half of the graph goes back to unvisited
// branches (bounds kept) and the search goes on: on Tiger with room for 16
// nodes (the whole graph has 27) the bounds still close on 19.37, in order and
// monotone all the way. (A limit below what one trial needs, 12 here, leaves
// the upper bound stuck above: a trial's path must fit.)
TEST(Pomhdp, ReclaimKeepsBoundsAndGoesOn) {
  const auto file = std::filesystem::path(PLR_POMDP_BENCHMARKS) / "Tiger.pomdp";
  auto m = load_model(file);
  ASSERT_TRUE(m) << m.error().message;
  const TabularHeuristics h = make_tabular_heuristics(*m);
  PomhdpOptions o;
  o.target_gap = 0.01;
  o.max_nodes = 16;
  Pomhdp solver(*m, *h.upper, *h.lower, h.inadmissible(), o);
  double lower = solver.lower(), upper = solver.upper();
  for (int i = 0; i < 500 && solver.upper() - solver.lower() > 0.01; ++i) {
    solver.solve(trials(20));
    EXPECT_LE(solver.num_nodes(), 16u);
    EXPECT_LE(solver.lower(), 19.3722);
    EXPECT_GE(solver.upper(), 19.3713);
    EXPECT_GE(solver.lower(), lower);
    EXPECT_LE(solver.upper(), upper);
    lower = solver.lower();
    upper = solver.upper();
  }
  EXPECT_GT(solver.reclaims(), 0u);
  EXPECT_NEAR(solver.lower(), 19.371, 0.02);
  EXPECT_NEAR(solver.upper(), 19.371, 0.02);
}

// Goal-directed (discount 1, costs): each try reaches the goal with
// probability 1/2 and costs 1, and the robot sees whether it got there, so
// V(start) = -1 + V(start) / 2, V = -2.
TEST(Pomhdp, GoalDirectedByHand) {
  const TabularModel m = parse_or_die(R"(discount: 1
states: start goal
actions: try
observations: not-yet there
T: try : start : start 0.5
T: try : start : goal 0.5
T: try : goal : goal 1
O: try : start : not-yet 1
O: try : goal : there 1
R: try : start : * : * -1
start: start
)",
                                      "goal");
  ASSERT_TRUE(m.is_terminal(1));
  const ConstantValue upper("zero", 0.0), lower("ten-steps", -10.0);
  Pomhdp solver(m, upper, lower, {});
  solver.solve(trials(50));
  EXPECT_NEAR(solver.upper(), -2.0, 1e-3);
  EXPECT_NEAR(solver.lower(), -2.0, 1e-3);
  // start loops on itself; the goal is a terminal branch, not a node.
  EXPECT_EQ(solver.num_nodes(), 1u);
}

// A tabular model seen through the generative interface only; the models
// below change one thing each.
class Forwarding : public GenerativeModel {
 public:
  explicit Forwarding(const TabularModel& m) : m_(m) {}
  int num_actions() const override { return m_.num_actions(); }
  int num_observations() const override { return m_.num_observations(); }
  double discount() const override { return m_.discount(); }
  double min_reward() const override { return m_.min_reward(); }
  double max_reward() const override { return m_.max_reward(); }
  Belief initial_belief() const override { return m_.initial_belief(); }
  bool is_terminal(StateId s) const override { return m_.is_terminal(s); }
  Step step(StateId s, ActionId a, Rng& rng) const override { return m_.step(s, a, rng); }

 protected:
  const TabularModel& m_;
};

// A model known only through step(): beliefs come from simulated particles
// (the default expand()), bounds from constants, as a simulator-backed model
// such as the truck's would have them.
class SimulatedOnly final : public Forwarding {
 public:
  explicit SimulatedOnly(const TabularModel& m) : Forwarding(m) { samples_per_particle = 4; }
};

TEST(Pomhdp, ParticleBeliefsOfASimulatedModel) {
  const TabularModel exact = parse_or_die(kSense, "sense");
  const SimulatedOnly m(exact);
  // Trivial bounds: +-1 a step forever, 2 and -2 with g = 0.5.
  const ConstantValue upper("max", 2.0), lower("min", -2.0);
  const RolloutValue rollout(m, 8, 10, 3);
  PomhdpOptions o;
  o.max_depth = 12;
  Pomhdp solver(m, upper, lower, {&rollout}, o);
  const ActionId a = solver.plan(trials(3000));
  EXPECT_EQ(a, 0);  // sense
  // Sensing is exact, so the sensed beliefs are single particles and the
  // bounds close on V* = 1 as they would on the exact model.
  EXPECT_NEAR(solver.lower(), 1.0, 0.05);
  EXPECT_LE(solver.lower(), solver.upper());
}

// Three ways to wait (0.5 each) and "go" (10, to the goal); a step counter
// is part of the state, as in the truck model, and at step 3 only going
// avoids the horizon's 100. V(s0) = -10. Under the zero upper bound each
// wait looks best until its own child is proven, so a search that may wait
// spends trial after trial on waits. A model that says a wait is dominated
// (it only spends time) is solved in one trial.
class WaitIsDominated final : public Forwarding {
 public:
  WaitIsDominated(const TabularModel& m, bool say) : Forwarding(m), say_(say) {}
  Expansion expand(const Belief& b, ActionId a, Rng& rng) const override {
    return m_.expand(b, a, rng);
  }
  // The waits, as the truck model says of an action that was not applicable.
  bool dominated(const Belief&, ActionId a) const override { return say_ && a < 3; }

 private:
  bool say_;
};

TEST(Pomhdp, ADominatedActionIsNotSearched) {
  const TabularModel m = parse_or_die(R"(discount: 1
states: s0 s1 s2 s3 goal
actions: wait1 wait2 wait3 go
observations: here there
T: wait1 : s0 : s1 1
T: wait2 : s0 : s1 1
T: wait3 : s0 : s1 1
T: wait1 : s1 : s2 1
T: wait2 : s1 : s2 1
T: wait3 : s1 : s2 1
T: wait1 : s2 : s3 1
T: wait2 : s2 : s3 1
T: wait3 : s2 : s3 1
T: wait1 : s3 : goal 1
T: wait2 : s3 : goal 1
T: wait3 : s3 : goal 1
T: go : * : goal 1
T: * : goal : goal 1
O: * : s0 : here 1
O: * : s1 : here 1
O: * : s2 : here 1
O: * : s3 : here 1
O: * : goal : there 1
R: wait1 : * : * : * -0.5
R: wait2 : * : * : * -0.5
R: wait3 : * : * : * -0.5
R: wait1 : s3 : * : * -100
R: wait2 : s3 : * : * -100
R: wait3 : s3 : * : * -100
R: go : * : * : * -10
R: * : goal : * : * 0
start: s0
)",
                                      "waits");
  const ConstantValue upper("zero", 0.0), lower("far", -200.0);
  const WaitIsDominated with(m, true), without(m, false);
  Pomhdp a(with, upper, lower, {});
  a.solve(trials(1000));
  EXPECT_EQ(a.total_trials(), 1u);
  EXPECT_NEAR(a.upper(), -10.0, 1e-9);
  EXPECT_NEAR(a.lower(), -10.0, 1e-9);
  EXPECT_EQ(a.best_action(), 3);
  Pomhdp b(without, upper, lower, {});
  b.solve(trials(1000));
  EXPECT_GT(b.total_trials(), a.total_trials());
  EXPECT_NEAR(b.upper(), -10.0, 1e-6);
}

// All actions dominated: the search keeps them all rather than none.
TEST(Pomhdp, AllActionsDominatedKeepsThemAll) {
  const TabularModel m = parse_or_die(R"(discount: 1
states: start goal
actions: wait
observations: here
T: wait : start : start 1
T: wait : goal : goal 1
O: * : * : here 1
R: wait : start : * : * -0.5
start: start
)",
                                      "goal");
  const ConstantValue upper("zero", 0.0), lower("far", -100.0);
  const WaitIsDominated with(m, true);
  PomhdpOptions o;
  o.max_depth = 4;
  Pomhdp a(with, upper, lower, {}, o);
  a.solve(trials(3));
  EXPECT_TRUE(std::isfinite(a.upper()));
  EXPECT_LT(a.upper(), 0.0);
}

// POMCP on the sense model learns to sense first; its value estimate of
// sensing approaches V* = 1.
TEST(Pomcp, SenseFirst) {
  const TabularModel m = parse_or_die(kSense, "sense");
  Pomcp solver(m);
  const ActionId a = solver.plan(trials(20000));
  EXPECT_EQ(a, 0);
  EXPECT_EQ(solver.last_stats().iterations, 20000u);
  EXPECT_GT(solver.root_visits(0), solver.root_visits(1));
  EXPECT_NEAR(solver.root_value(0), 1.0, 0.2);
  // The subtree of the taken branch is kept.
  const std::size_t before = solver.num_nodes();
  solver.advance(0, 0, Belief({{0, 1.0}}));
  EXPECT_LT(solver.num_nodes(), before);
  EXPECT_GT(solver.num_nodes(), 1u);
}

// The MDP's greedy actions on the sense model: pick the side the state is on.
// On the bandit: stay in s0 (1 a step against 0), go in s1 (2 against 0).
TEST(Heuristics, MdpGreedyActionsByHand) {
  const TabularModel sense = parse_or_die(kSense, "sense");
  EXPECT_EQ(make_tabular_heuristics(sense).mdp_greedy, (std::vector<ActionId>{1, 2}));
  const TabularModel bandit = parse_or_die(kBandit, "bandit");
  EXPECT_EQ(make_tabular_heuristics(bandit).mdp_greedy, (std::vector<ActionId>{0, 1}));
}

// Rollouts below the tree follow the given policy on the sampled state.
TEST(Pomcp, RolloutPolicy) {
  const TabularModel m = parse_or_die(kSense, "sense");
  int calls = 0;
  const auto greedy = rollout_policy_from({1, 2});
  PomcpOptions o;
  o.rollout_policy = [&](StateId s, Rng& rng) {
    ++calls;
    return greedy(s, rng);
  };
  Pomcp solver(m, o);
  EXPECT_EQ(solver.plan(trials(2000)), 0);  // sense
  EXPECT_GT(calls, 0);
  // Rollouts that always pick right earn 2 from a known state: sensing is
  // worth 0 + g * 2 = 1 in expectation, and picking blind 0 + ... = 0.
  EXPECT_NEAR(solver.root_value(0), 1.0, 0.2);
}

// Warm starts: reset() to the same initial belief keeps the tree (POMCP) or
// the graph (POMHDP) and its statistics; another belief starts afresh.
TEST(Pomcp, WarmStartKeepsTheTree) {
  const TabularModel m = parse_or_die(kSense, "sense");
  for (const bool warm : {false, true}) {
    PomcpOptions o;
    o.warm_start = warm;
    Pomcp solver(m, o);
    solver.plan(trials(500));
    const std::uint32_t visits = solver.root_visits(0);
    solver.advance(0, 0, Belief({{0, 1.0}}));
    solver.plan(trials(100));
    solver.reset(m.initial_belief());
    EXPECT_EQ(solver.root_visits(0), warm ? visits : 0u);
    solver.reset(Belief({{1, 1.0}}));
    EXPECT_EQ(solver.root_visits(0), 0u);
  }
}

TEST(Pomhdp, WarmStartKeepsTheGraph) {
  const TabularModel m = parse_or_die(kSense, "sense");
  const TabularHeuristics h = make_tabular_heuristics(m);
  for (const bool warm : {false, true}) {
    PomhdpOptions o;
    o.warm_start = warm;
    Pomhdp solver(m, *h.upper, *h.lower, {}, o);
    EXPECT_NEAR(solver.lower(), 0.0, 1e-5);  // the blind bound
    solver.plan(trials(100));
    EXPECT_NEAR(solver.lower(), 1.0, 1e-6);
    solver.advance(0, 0, Belief({{0, 1.0}}));
    solver.reset(m.initial_belief());
    EXPECT_NEAR(solver.lower(), warm ? 1.0 : 0.0, 1e-5);
  }
}

// Episodes on two workers are the episodes one worker runs: each has its own
// random stream, and a trial budget makes each search deterministic.
TEST(Evaluate, WorkersDoNotChangeEpisodes) {
  const auto file = std::filesystem::path(PLR_POMDP_BENCHMARKS) / "Tiger.pomdp";
  auto m = load_model(file);
  ASSERT_TRUE(m) << m.error().message;
  const TabularHeuristics h = make_tabular_heuristics(*m);
  const auto make = [&](int) {
    return std::make_unique<Pomhdp>(*m, *h.upper, *h.lower, h.inadmissible());
  };
  EvaluationOptions eo;
  eo.episodes = 24;
  eo.max_steps = 30;
  eo.per_step = trials(50);
  const Evaluation one = evaluate(*m, make, eo);
  eo.workers = 2;
  int calls = 0;
  eo.progress = [&](int done, int total) {
    EXPECT_EQ(done, ++calls);
    EXPECT_EQ(total, 24);
  };
  const Evaluation two = evaluate(*m, make, eo);
  EXPECT_EQ(calls, 24);
  ASSERT_EQ(one.returns.size(), 24u);
  EXPECT_EQ(one.returns, two.returns);
  EXPECT_DOUBLE_EQ(one.mean, two.mean);
}

TEST(Evaluate, ConfidenceIntervalByHand) {
  Evaluation e;
  e.returns = {1.0, 2.0, 3.0, 4.0};
  summarize(e);
  EXPECT_DOUBLE_EQ(e.mean, 2.5);
  // sd = sqrt(5/3), t(3) = 3.182.
  EXPECT_NEAR(e.ci95, 3.182 * std::sqrt(5.0 / 3.0) / 2.0, 1e-9);
}

// Control variate by hand: X = 0..4 (mean 2, known mean 2.5), Y = 1 4 4 8 9
// (mean 5.2): beta = Sxy / Sxx = 20 / 10 = 2, estimate 5.2 - 2 (2 - 2.5) = 6.2;
// residuals -0.2 0.8 -1.2 0.8 -0.2, s^2 = 2.8 / 3, standard error
// sqrt(s^2 (1/5 + 0.25/10)) = sqrt(0.21), t(3) = 3.182.
TEST(Evaluate, ControlVariateByHand) {
  Evaluation e;
  e.returns = {1.0, 4.0, 4.0, 8.0, 9.0};
  e.controls = {0.0, 1.0, 2.0, 3.0, 4.0};
  summarize_with_control(e, 2.5);
  EXPECT_NEAR(e.cv_beta, 2.0, 1e-12);
  EXPECT_NEAR(e.cv_mean, 6.2, 1e-12);
  EXPECT_NEAR(e.cv_ci95, 3.182 * std::sqrt(0.21), 1e-9);
  // A control that differs only by rounding leaves the plain estimate.
  e.controls = {1.0, 1.0 + 1e-15, 1.0, 1.0 - 1e-15, 1.0};
  summarize(e);
  summarize_with_control(e, 1.0);
  EXPECT_EQ(e.cv_beta, 0.0);
  EXPECT_EQ(e.cv_mean, e.mean);
  EXPECT_EQ(e.cv_ci95, e.ci95);
}

}  // namespace
}  // namespace plr::pomdp
