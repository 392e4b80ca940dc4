// The ARA* lattice planner: one entry point for every mode.
//
//   plr::arastar::Planner planner(LatticeConfig::from_file(".../unloader.yaml"));
//   plr::sim::PlanResult r = planner.plan(query, checker);
//
// M1/M2/M3/M5 run ARA* on the joint lattice (ε from the query's schedule,
// improved while improve_time_s allows), M4 runs A* along the plate's line,
// M6 (and any query whose start collides) runs Dijkstra to the nearest
// collision-free state. Search memory is kept between queries, so one Planner
// per thread.
#pragma once

#include "lattice/lattice_config.hpp"
#include "plr/sim/plan_types.hpp"
#include "search/arastar.hpp"

namespace plr::arastar {

class Planner {
 public:
  explicit Planner(LatticeConfig config);

  // The checker must be built on the query's world; the query's held and
  // ignored boxes are applied to it for the duration of the call.
  sim::PlanResult plan(const sim::PlanQuery& query, sim::CollisionChecker& checker);

  const LatticeConfig& config() const { return config_; }

 private:
  struct Escape {
    sim::PlanStatus status = sim::PlanStatus::kNoPath;
    std::string why;  // when not solved
    std::vector<sim::JointVector> path;
  };
  Escape escape(const sim::JointVector& start, sim::CollisionChecker& checker,
                const sim::PlanQuery& query, sim::PlanStats& stats);

  LatticeConfig config_;
  search::AraStar search_;
};

}  // namespace plr::arastar
