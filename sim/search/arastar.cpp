#include "plr/search/arastar.hpp"

#include <time.h>

#include <algorithm>
#include <cmath>

namespace plr::search {
namespace {

double thread_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

}  // namespace

AraStar::Record& AraStar::record(StateId s) {
  if (static_cast<std::size_t>(s) >= records_.size())
    records_.resize(static_cast<std::size_t>(s) + 1);
  Record& r = records_[static_cast<std::size_t>(s)];
  if (r.search != search_stamp_) {
    r.search = search_stamp_;
    r.closed_iteration = 0;
    r.g = std::numeric_limits<double>::infinity();
    r.h = heuristic_->estimate(s);
    r.id = s;
    r.parent = kNoState;
    r.incons = false;
    r.heap_slot = 0;
  }
  return r;
}

AraStar::Stop AraStar::improve_path(Graph& graph, Clock::time_point deadline,
                                    std::size_t max_expansions, SearchResult& result) {
  std::size_t since_clock = 0;
  while (!open_.empty()) {
    const double goal_g = best_goal_ == kNoState ? std::numeric_limits<double>::infinity()
                                                 : records_[static_cast<std::size_t>(best_goal_)].g;
    if (open_.top_key() >= goal_g) break;
    if (max_expansions != 0 && result.expansions >= max_expansions) return Stop::kBudget;
    if (++since_clock == 8) {
      since_clock = 0;
      if (Clock::now() >= deadline) return Stop::kTime;
    }
    Record* r = open_.pop();
    r->closed_iteration = iteration_;
    ++result.expansions;
    const StateId id = r->id;
    const double g = r->g;
    successors_.clear();
    graph.successors(id, successors_);
    for (const Successor& succ : successors_) {
      Record& n = record(succ.id);  // may grow the deque; r stays valid
      const double ng = g + succ.cost;
      if (ng >= n.g) continue;
      n.g = ng;
      n.parent = id;
      if (graph.is_goal(succ.id)) {
        // Goals need no expansion: they end the path.
        if (best_goal_ == kNoState || ng < records_[static_cast<std::size_t>(best_goal_)].g)
          best_goal_ = succ.id;
        continue;
      }
      if (n.closed_iteration != iteration_) {
        n.key = key_of(n);
        n.tie = n.h;
        open_.push_or_update(&n);
      } else if (!n.incons) {
        n.incons = true;
        incons_.push_back(succ.id);
      }
    }
  }
  return Stop::kDone;
}

double AraStar::min_unexpanded_f() const {
  double f = std::numeric_limits<double>::infinity();
  for (const Record* r : open_.items()) f = std::min(f, r->g + r->h);
  for (StateId s : incons_) {
    const Record& r = records_[static_cast<std::size_t>(s)];
    f = std::min(f, r.g + r.h);
  }
  return f;
}

void AraStar::extract_path(SearchResult& result) const {
  result.path.clear();
  for (StateId s = best_goal_; s != kNoState; s = records_[static_cast<std::size_t>(s)].parent) {
    result.path.push_back(s);
  }
  std::reverse(result.path.begin(), result.path.end());
  result.cost = records_[static_cast<std::size_t>(best_goal_)].g;
}

SearchResult AraStar::search(Graph& graph, Heuristic& heuristic, StateId start,
                             const SearchOptions& options) {
  const auto t0 = Clock::now();
  auto deadline = std::isinf(options.time_limit_s)
                      ? Clock::time_point::max()
                      : t0 + std::chrono::duration_cast<Clock::duration>(
                                 std::chrono::duration<double>(options.time_limit_s));
  auto elapsed = [&] { return std::chrono::duration<double>(Clock::now() - t0).count(); };

  const double cpu0 = thread_cpu_seconds();
  heuristic_ = &heuristic;
  ++search_stamp_;
  iteration_ = 1;
  open_.clear();
  incons_.clear();
  best_goal_ = kNoState;
  eps_ = std::max(1.0, options.eps_initial);
  const double eps_final = std::clamp(options.eps_final, 1.0, eps_);

  SearchResult result;
  Record& s0 = record(start);
  s0.g = 0.0;
  if (graph.is_goal(start)) {
    best_goal_ = start;
  } else {
    s0.key = key_of(s0);
    s0.tie = s0.h;
    open_.push(&s0);
  }

  for (;;) {
    const Stop stop = improve_path(graph, deadline, options.max_expansions, result);
    if (stop != Stop::kDone) {
      result.budget_exhausted = stop == Stop::kBudget;
      result.time_limit_hit = stop == Stop::kTime;
      break;
    }
    ++result.iterations;
    if (best_goal_ == kNoState) break;  // OPEN exhausted: no path at any ε
    const bool first = result.path.empty();
    extract_path(result);
    result.final_eps = eps_;
    // ARA*'s bound: cost / min over unexpanded states of g + h.
    const double lower = min_unexpanded_f();
    result.suboptimality_bound =
        std::min(eps_, std::isinf(lower) ? 1.0 : std::max(1.0, result.cost / lower));
    if (first) {
      result.first_solution_time_s = elapsed();
      result.first_solution_cpu_s = thread_cpu_seconds() - cpu0;
      result.first_solution_expansions = result.expansions;
      if (std::isfinite(options.improve_time_s) && options.max_expansions == 0) {
        deadline = std::min(
            deadline, Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                         std::chrono::duration<double>(options.improve_time_s)));
      }
    }
    if (options.first_solution_only || eps_ <= eps_final || result.suboptimality_bound <= 1.0)
      break;
    // Next iteration: smaller ε, INCONS back into OPEN, keys recomputed,
    // CLOSED emptied by moving to a new iteration number.
    eps_ = std::max(eps_final, eps_ - options.eps_decrement);
    ++iteration_;
    for (StateId s : incons_) {
      Record& r = records_[static_cast<std::size_t>(s)];
      r.incons = false;
      if (!open_.contains(&r)) open_.push(&r);
    }
    incons_.clear();
    for (Record* r : open_.items()) r->key = key_of(*r);
    open_.rebuild();
  }

  if (!result.path.empty()) {
    result.status = SearchStatus::kSolved;
  } else {
    result.status = open_.empty() ? SearchStatus::kNoPath : SearchStatus::kTimeout;
  }
  result.time_s = elapsed();
  return result;
}

SearchResult astar(Graph& graph, Heuristic& heuristic, StateId start, double weight) {
  AraStar s;
  SearchOptions o;
  o.eps_initial = o.eps_final = weight;
  return s.search(graph, heuristic, start, o);
}

SearchResult dijkstra(Graph& graph, StateId start) {
  ZeroHeuristic zero;
  return astar(graph, zero, start, 1.0);
}

}  // namespace plr::search
