// The ARA* lattice planner, the paper's: anytime search over a state lattice
// of motion primitives, plus adaptive primitives that snap to the goal.
//
//   auto config = plr::planning::LatticeConfig::from_file(
//       plr::sim::shipped_file("robots/unloader_lattice.yaml"));
//   plr::planning::LatticePlanner planner(*config);
//   plr::planning::PlanResult r = planner.plan(query, checker);
//
// M1/M2/M3/M5 run ARA* on the joint lattice (ε from the query's schedule,
// improved while improve_time_s allows), M4 runs A* along the plate's line.
// Search memory is kept between queries, so one planner per thread.
#pragma once

#include <memory>

#include "plr/planning/lattice_config.hpp"
#include "plr/planning/planner.hpp"

namespace plr::planning {

class LatticePlanner final : public Planner {
 public:
  explicit LatticePlanner(LatticeConfig config);
  ~LatticePlanner() override;

  std::string name() const override { return "arastar"; }
  const LatticeConfig& config() const { return config_; }

 protected:
  PlanResult do_plan(const PlanQuery& query, sim::CollisionChecker& checker) override;

 private:
  LatticeConfig config_;
  std::unique_ptr<search::AraStar> search_;
};

}  // namespace plr::planning
