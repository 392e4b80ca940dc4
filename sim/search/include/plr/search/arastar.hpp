// ARA* (Likhachev, Gordon, Thrun 2003) and its special cases: weighted A*
// (one iteration at a fixed ε), A* (ε = 1) and Dijkstra (zero heuristic).
//
// Search memory (per-state records, heap, INCONS list) belongs to the search
// object and is reused by the next search: records are stamped with a search
// number and reset lazily when first touched, so a new search allocates only
// for states never seen before.
#pragma once

#include <chrono>
#include <cstddef>
#include <deque>
#include <limits>
#include <vector>

#include "plr/search/graph.hpp"
#include "plr/search/intrusive_heap.hpp"

namespace plr::search {

struct SearchOptions {
  double eps_initial = 1.0;    // first iteration's heuristic weight
  double eps_final = 1.0;      // stop improving once this ε is done
  double eps_decrement = 0.5;  // ε step between iterations
  double time_limit_s = std::numeric_limits<double>::infinity();
  // Once a solution exists, improve it for at most this long. Ignored with an
  // expansion budget: how far ε gets must not depend on the machine's load.
  double improve_time_s = std::numeric_limits<double>::infinity();
  // Stop after this many expansions (0 = no budget) with the solution of the
  // last completed iteration: the same search then always ends the same way.
  std::size_t max_expansions = 0;
  // Stop at the first solution instead of improving it while time remains.
  bool first_solution_only = false;
};

enum class SearchStatus { kSolved, kNoPath, kTimeout };

struct SearchResult {
  SearchStatus status = SearchStatus::kNoPath;
  std::vector<StateId> path;  // start .. goal
  double cost = std::numeric_limits<double>::infinity();
  // cost <= bound * optimal cost (1 once an ε = 1 iteration completed).
  double suboptimality_bound = std::numeric_limits<double>::infinity();
  double final_eps = 0.0;  // ε of the last completed iteration
  int iterations = 0;      // completed ImprovePath calls
  std::size_t expansions = 0;
  std::size_t first_solution_expansions = 0;
  bool budget_exhausted = false;  // max_expansions ended the search
  bool time_limit_hit = false;    // time_limit_s (or improve_time_s) ended it
  double first_solution_time_s = 0.0;
  double first_solution_cpu_s = 0.0;  // this thread's CPU time
  double time_s = 0.0;
};

class AraStar {
 public:
  SearchResult search(Graph& graph, Heuristic& heuristic, StateId start,
                      const SearchOptions& options);

 private:
  struct Record : HeapElement {
    unsigned search = 0;  // stamp; stale records are reset on first touch
    unsigned closed_iteration = 0;
    double g = 0.0;
    double h = 0.0;
    StateId id = kNoState;
    StateId parent = kNoState;
    bool incons = false;
  };
  using Clock = std::chrono::steady_clock;

  Record& record(StateId s);
  double key_of(const Record& r) const { return r.g + eps_ * r.h; }
  enum class Stop { kDone, kTime, kBudget };
  // kDone when the iteration completed (solution proven at ε or OPEN empty).
  Stop improve_path(Graph& graph, Clock::time_point deadline, std::size_t max_expansions,
                    SearchResult& result);
  void extract_path(SearchResult& result) const;
  double min_unexpanded_f() const;

  std::deque<Record> records_;  // by StateId; a deque keeps addresses stable
  IntrusiveHeap<Record> open_;
  std::vector<StateId> incons_;
  std::vector<Successor> successors_;
  Heuristic* heuristic_ = nullptr;
  unsigned search_stamp_ = 0;
  unsigned iteration_ = 0;
  double eps_ = 1.0;
  StateId best_goal_ = kNoState;
};

// Conveniences over one AraStar run.
SearchResult astar(Graph& graph, Heuristic& heuristic, StateId start, double weight = 1.0);
SearchResult dijkstra(Graph& graph, StateId start);

}  // namespace plr::search
