// The planner contract: what every motion planner (ARA* lattice, OMPL, one of
// your own) promises its callers, in-process or behind the `plan` service.
//
// A planner implements one hook, do_plan(). The public plan() is the same for
// every planner and does what they would otherwise each repeat: it checks the
// query, applies its held and ignored boxes to the checker, judges the start
// and the goal before any search (so every planner answers a bad start or
// goal with the same status), leaves a start in collision with the M6 escape
// (Dijkstra to the nearest collision-free state on the M6 lattice), times the
// path within the robot's limits, and fills the statistics.
//
//   class MyPlanner : public plr::planning::Planner {
//    public:
//     std::string name() const override { return "my_planner"; }
//    protected:
//     plr::planning::PlanResult do_plan(const plr::planning::PlanQuery& q,
//                                       plr::sim::CollisionChecker& checker) override;
//   };
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "plr/planning/lattice_config.hpp"
#include "plr/planning/plan_query.hpp"

namespace plr::search {
class AraStar;
}

namespace plr::planning {

class Planner {
 public:
  // `escape` is the lattice of the M6 escape (the shipped one by default).
  explicit Planner(ModeLattice escape = default_escape_lattice());
  virtual ~Planner();
  Planner(const Planner&) = delete;
  Planner& operator=(const Planner&) = delete;

  // Answers one query. The checker must be built on the query's world; the
  // query's held and ignored boxes apply to it for the duration of the call.
  // Never throws: a bad query is answered with kInvalidRequest and the reason.
  PlanResult plan(const PlanQuery& query, sim::CollisionChecker& checker);

  // Names the planner in responses and statistics ("arastar", "rrtconnect").
  virtual std::string name() const = 0;
  // The modes do_plan() handles; a query in another mode is answered with
  // kInvalidRequest. M6 is handled here and never reaches do_plan().
  virtual std::vector<PlanMode> modes() const;

 protected:
  // Plans from a valid start (within limits and collision-free) to a goal
  // that plan() found reachable. `query.time_limit_s` and
  // `query.max_expansions` are what the escape left. Returns the path (start
  // first); the trajectory may be left empty, plan() times the path.
  // stats.expansions, first_solution_* and cost are the hook's to fill.
  virtual PlanResult do_plan(const PlanQuery& query, sim::CollisionChecker& checker) = 0;

  // CPU time of the calling thread (s), for first_solution_cpu_s: what a
  // query costs whatever else the machine is doing.
  static double thread_cpu_seconds();

 private:
  struct Escaped;
  Escaped escape(const PlanQuery& query, sim::CollisionChecker& checker);

  ModeLattice escape_lattice_;
  std::unique_ptr<search::AraStar> escape_search_;
};

}  // namespace plr::planning
