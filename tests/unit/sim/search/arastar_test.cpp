#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <random>

#include "plr/search/arastar.hpp"
#include "plr/search/grid.hpp"
#include "plr/search/intrusive_heap.hpp"

using namespace plr::search;

namespace {

struct Item : HeapElement {
  int value = 0;
};

// Explicit weighted digraph with a per-state heuristic table.
class TableGraph final : public Graph, public Heuristic {
 public:
  void edge(StateId a, StateId b, double c) { edges_[a].push_back({b, c}); }
  void successors(StateId s, std::vector<Successor>& out) override {
    ++expanded;
    const auto it = edges_.find(s);
    if (it != edges_.end()) out.insert(out.end(), it->second.begin(), it->second.end());
  }
  bool is_goal(StateId s) override { return s == goal; }
  double estimate(StateId s) override { return h.count(s) ? h[s] : 0.0; }
  StateId goal = kNoState;
  std::map<StateId, double> h;
  int expanded = 0;

 private:
  std::map<StateId, std::vector<Successor>> edges_;
};

}  // namespace

TEST(IntrusiveHeap, PopsInKeyOrderAfterUpdates) {
  std::vector<Item> items(200);
  IntrusiveHeap<Item> heap;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0, 100);
  for (auto& it : items) {
    it.key = u(rng);
    heap.push(&it);
  }
  // Change half the keys in both directions.
  for (std::size_t i = 0; i < items.size(); i += 2) {
    items[i].key = u(rng);
    heap.update(&items[i]);
  }
  double last = -1;
  std::size_t n = 0;
  while (!heap.empty()) {
    Item* it = heap.pop();
    EXPECT_FALSE(heap.contains(it));
    EXPECT_GE(it->key, last);
    last = it->key;
    ++n;
  }
  EXPECT_EQ(n, items.size());
}

TEST(IntrusiveHeap, TieBreaksOnSecondKey) {
  Item a, b;
  a.key = b.key = 1.0;
  a.tie = 2.0;
  b.tie = 1.0;
  IntrusiveHeap<Item> heap;
  heap.push(&a);
  heap.push(&b);
  EXPECT_EQ(heap.pop(), &b);
}

TEST(Search, AStarFindsCheapestOfTwoRoutes) {
  TableGraph g;
  // 0 -> 1 -> 3 costs 2 + 2; 0 -> 2 -> 3 costs 1 + 5.
  g.edge(0, 1, 2);
  g.edge(1, 3, 2);
  g.edge(0, 2, 1);
  g.edge(2, 3, 5);
  g.goal = 3;
  const auto r = astar(g, g, 0);
  ASSERT_EQ(r.status, SearchStatus::kSolved);
  EXPECT_EQ(r.path, (std::vector<StateId>{0, 1, 3}));
  EXPECT_DOUBLE_EQ(r.cost, 4.0);
}

TEST(Search, NoPathWhenGoalUnreachable) {
  TableGraph g;
  g.edge(0, 1, 1);
  g.edge(1, 0, 1);
  g.goal = 7;
  const auto r = dijkstra(g, 0);
  EXPECT_EQ(r.status, SearchStatus::kNoPath);
  EXPECT_TRUE(r.path.empty());
}

TEST(Search, StartThatIsGoalCostsNothing) {
  TableGraph g;
  g.goal = 0;
  const auto r = dijkstra(g, 0);
  ASSERT_EQ(r.status, SearchStatus::kSolved);
  EXPECT_EQ(r.path, (std::vector<StateId>{0}));
  EXPECT_EQ(r.cost, 0.0);
}

TEST(Search, WeightedAStarTakesGreedyRouteAndAraStarImprovesIt) {
  // A misleading heuristic: the direct route looks cheaper than it is.
  TableGraph g;
  g.edge(0, 1, 1);
  g.edge(1, 9, 10);  // cost 11 via 1
  g.edge(0, 2, 3);
  g.edge(2, 3, 3);
  g.edge(3, 9, 3);  // cost 9 via 2, 3
  g.goal = 9;
  g.h = {{0, 9}, {1, 1}, {2, 6}, {3, 3}};
  const auto w = astar(g, g, 0, 3.0);
  ASSERT_EQ(w.status, SearchStatus::kSolved);
  EXPECT_DOUBLE_EQ(w.cost, 11.0);
  EXPECT_LE(w.cost, 3.0 * 9.0);

  AraStar ara;
  SearchOptions o;
  o.eps_initial = 3.0;
  o.eps_final = 1.0;
  o.eps_decrement = 1.0;
  const auto r = ara.search(g, g, 0, o);
  ASSERT_EQ(r.status, SearchStatus::kSolved);
  EXPECT_DOUBLE_EQ(r.cost, 9.0);
  EXPECT_EQ(r.final_eps, 1.0);
  EXPECT_DOUBLE_EQ(r.suboptimality_bound, 1.0);
  EXPECT_GE(r.iterations, 2);
}

TEST(Search, AraStarBoundHoldsOnGridsAtEveryEpsilon) {
  const auto map = load_grid_map(PLR_MOVINGAI_DIR "/den011d.map");
  const auto queries = load_scenario(PLR_MOVINGAI_DIR "/den011d.map.scen");
  GridGraph graph(map);
  OctileHeuristic h(map);
  AraStar ara;
  for (std::size_t i = 0; i < queries.size(); i += 37) {
    const auto& q = queries[i];
    graph.set_goal(q.goal_x, q.goal_y);
    h.set_goal(q.goal_x, q.goal_y);
    for (bool first_only : {true, false}) {
      SearchOptions o;
      o.eps_initial = 3.0;
      o.eps_final = 1.0;
      o.first_solution_only = first_only;
      const auto r = ara.search(graph, h, graph.id(q.start_x, q.start_y), o);
      ASSERT_EQ(r.status, SearchStatus::kSolved);
      // The reported bound is honest: cost <= bound * optimum (the published
      // optima are rounded, hence the tolerance).
      EXPECT_LE(r.cost, r.suboptimality_bound * q.optimal + 0.01) << i;
      EXPECT_LE(r.suboptimality_bound, 3.0);
      if (!first_only) {
        EXPECT_NEAR(r.cost, q.optimal, 0.01) << i;
      }
    }
  }
}

TEST(Search, TimeLimitStopsASearchWithoutSolution) {
  // A graph that never ends, goal unreachable.
  class Line final : public Graph {
   public:
    void successors(StateId s, std::vector<Successor>& out) override {
      out.push_back({s + 1, 1.0});
    }
    bool is_goal(StateId) override { return false; }
  } line;
  ZeroHeuristic zero;
  AraStar ara;
  SearchOptions o;
  o.time_limit_s = 0.02;
  const auto r = ara.search(line, zero, 0, o);
  EXPECT_EQ(r.status, SearchStatus::kTimeout);
  EXPECT_TRUE(r.time_limit_hit);
  EXPECT_FALSE(r.budget_exhausted);
}

TEST(Search, ExpansionBudgetEndsTheSearchTheSameWayEveryTime) {
  // The misleading graph above: ε = 3 finds the cost-11 route after 2
  // expansions, ε = 2 completes without one, ε = 1 needs 2 more for cost 9.
  TableGraph g;
  g.edge(0, 1, 1);
  g.edge(1, 9, 10);
  g.edge(0, 2, 3);
  g.edge(2, 3, 3);
  g.edge(3, 9, 3);
  g.goal = 9;
  g.h = {{0, 9}, {1, 1}, {2, 6}, {3, 3}};
  AraStar ara;
  SearchOptions o;
  o.eps_initial = 3.0;
  o.eps_final = 1.0;
  o.eps_decrement = 1.0;
  o.improve_time_s = 0.0;  // would stop at the first solution without a budget
  o.max_expansions = 3;
  const auto r = ara.search(g, g, 0, o);
  ASSERT_EQ(r.status, SearchStatus::kSolved);
  EXPECT_TRUE(r.budget_exhausted);
  EXPECT_FALSE(r.time_limit_hit);
  EXPECT_EQ(r.expansions, 3u);
  EXPECT_DOUBLE_EQ(r.cost, 11.0);  // the last completed iteration's
  EXPECT_EQ(r.final_eps, 2.0);

  o.max_expansions = 100;  // enough for ε = 1, improve_time_s ignored
  const auto full = ara.search(g, g, 0, o);
  EXPECT_FALSE(full.budget_exhausted);
  EXPECT_DOUBLE_EQ(full.cost, 9.0);
  EXPECT_EQ(full.final_eps, 1.0);

  o.max_expansions = 1;  // before any solution
  const auto none = ara.search(g, g, 0, o);
  EXPECT_EQ(none.status, SearchStatus::kTimeout);
  EXPECT_TRUE(none.budget_exhausted);
}

// Every query of the three shipped Moving AI maps at the published optimum.
class MovingAi : public ::testing::TestWithParam<const char*> {};

TEST_P(MovingAi, AStarMatchesPublishedOptimum) {
  const std::string base = std::string(PLR_MOVINGAI_DIR "/") + GetParam();
  const auto map = load_grid_map(base);
  const auto queries = load_scenario(base + ".scen");
  ASSERT_FALSE(queries.empty());
  GridGraph graph(map);
  OctileHeuristic h(map);
  AraStar search;
  std::size_t mismatches = 0;
  for (const auto& q : queries) {
    graph.set_goal(q.goal_x, q.goal_y);
    h.set_goal(q.goal_x, q.goal_y);
    SearchOptions o;
    const auto r = search.search(graph, h, graph.id(q.start_x, q.start_y), o);
    ASSERT_EQ(r.status, SearchStatus::kSolved);
    if (std::abs(r.cost - q.optimal) > 0.01) ++mismatches;
  }
  EXPECT_EQ(mismatches, 0u);
}

INSTANTIATE_TEST_SUITE_P(Maps, MovingAi,
                         ::testing::Values("arena.map", "den011d.map", "random512-10-0.map"));

TEST(Grid, BadFilesNameFileAndCause) {
  try {
    load_grid_map("/nonexistent.map");
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "/nonexistent.map: cannot open file");
  }
}
